// A depth image by its file's extension: the one dispatch between the .npy and PNG readers,
// for the frames' readers and the command line's size probe.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>

#include "femreg/camera_io.h"
#include "io/io_internal.h"

namespace femreg {

Status ReadDepthImageFile(const std::string& path, RawDepthImage* image) {
  const std::string ext = internal::LowercaseExtension(path);
  if (ext == ".npy") return ReadDepthNpy(path, image);
  if (ext == ".png") return ReadDepthPng(path, image);
  return Status::Error(path + ": not a depth image file (a depth image is a .png or a .npy)");
}

}  // namespace femreg
