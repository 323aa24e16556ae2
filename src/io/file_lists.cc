// Lists of files: a folder's files of some types, or a glob pattern's matches, in natural
// order of names.
#include <glob.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "femreg/io.h"

namespace femreg {
namespace {

namespace fs = std::filesystem;

// Natural order: "frame_10" after "frame_9".
bool NaturalLess(const std::string& a, const std::string& b) {
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (std::isdigit(static_cast<unsigned char>(a[i])) && std::isdigit(static_cast<unsigned char>(b[j]))) {
      size_t i2 = i, j2 = j;
      while (i2 < a.size() && std::isdigit(static_cast<unsigned char>(a[i2]))) ++i2;
      while (j2 < b.size() && std::isdigit(static_cast<unsigned char>(b[j2]))) ++j2;
      const std::string na = a.substr(i, i2 - i), nb = b.substr(j, j2 - j);
      const unsigned long long va = std::strtoull(na.c_str(), nullptr, 10);
      const unsigned long long vb = std::strtoull(nb.c_str(), nullptr, 10);
      if (va != vb) return va < vb;
      i = i2;
      j = j2;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i;
      ++j;
    }
  }
  return a.size() - i < b.size() - j;
}

}  // namespace

Status ListFiles(const std::string& dir_or_glob, const std::vector<std::string>& extensions,
                 std::vector<std::string>* files) {
  files->clear();
  std::error_code ec;
  if (fs::is_directory(dir_or_glob, ec)) {
    for (const auto& entry : fs::directory_iterator(dir_or_glob, ec)) {
      if (!entry.is_regular_file()) continue;
      std::string ext = entry.path().extension().string();
      std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
      if (std::find(extensions.begin(), extensions.end(), ext) != extensions.end()) {
        files->push_back(entry.path().string());
      }
    }
    if (files->empty()) {
      std::string list;
      for (const auto& e : extensions) list += (list.empty() ? "" : ", ") + e;
      return Status::Error(dir_or_glob + ": no frame files (" + list + ") in this folder");
    }
  } else {
    glob_t g;
    const int rc = glob(dir_or_glob.c_str(), 0, nullptr, &g);
    if (rc == 0) {
      for (size_t i = 0; i < g.gl_pathc; ++i) files->push_back(g.gl_pathv[i]);
    }
    globfree(&g);
    if (files->empty()) {
      return Status::Error(dir_or_glob + ": no such folder, and no file matches it as a pattern");
    }
  }
  std::sort(files->begin(), files->end(), NaturalLess);
  return Status::Ok();
}

}  // namespace femreg
