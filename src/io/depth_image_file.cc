// A depth image by its file's extension: the one dispatch between the .npy and PNG readers,
// for the frames' readers and the command line's size probe.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>

#include "femreg/camera_io.h"

namespace femreg {

Status ReadDepthImageFile(const std::string& path, RawDepthImage* image) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext == ".npy") return ReadDepthNpy(path, image);
  if (ext == ".png") return ReadDepthPng(path, image);
  return Status::Error(path + ": not a depth image file (a depth image is a .png or a .npy)");
}

}  // namespace femreg
