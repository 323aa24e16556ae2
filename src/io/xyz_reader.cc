// Text point clouds (.xyz, .txt, .csv): one point a line, 'x y z' or 'x y z nx ny nz', the
// values split by spaces, tabs, commas or semicolons; blank lines and '#' comments skipped.
// Also the look at a cloud file's first bytes that picks PLY, PCD or text.
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "io/io_internal.h"
#include "io/text_tokens.h"

namespace femreg {
namespace internal {

Status DetectCloudFormat(const std::string& path, CloudFileFormat* format) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Error(path + ": cannot open");
  std::string head(256, '\0');
  in.read(&head[0], static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(in.gcount()));
  // A PCD header is recognized by any of its keywords, so that one with a line missing
  // (FIELDS deleted, say) is refused as a PCD rather than read as text.
  auto pcd_key = [&](const char* key) {
    return head.compare(0, std::strlen(key), key) == 0 || head.find(std::string("\n") + key) != std::string::npos;
  };
  if (head.compare(0, 3, "ply") == 0) {
    *format = CloudFileFormat::kPly;
  } else if (head.find("# .PCD") != std::string::npos || pcd_key("VERSION") || pcd_key("FIELDS") ||
             pcd_key("SIZE") || pcd_key("TYPE") || pcd_key("WIDTH") || pcd_key("DATA")) {
    *format = CloudFileFormat::kPcd;
  } else {
    *format = CloudFileFormat::kText;
  }
  return Status::Ok();
}

Status ReadXyzCloud(const std::string& path, RawCloud* cloud) {
  std::ifstream in(path);
  if (!in) return Status::Error(path + ": cannot open");
  std::vector<double> pts, nrm;
  std::string line;
  int line_no = 0;
  int columns = -1;
  while (std::getline(in, line)) {
    ++line_no;
    const auto start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#') continue;
    for (char& c : line) {
      if (c == ',' || c == ';') c = ' ';
    }
    std::istringstream ls(line);
    std::vector<double> values;
    std::string token;
    while (ls >> token) {
      char* end = nullptr;
      const double v = std::strtod(token.c_str(), &end);
      if (end == token.c_str() || *end != '\0') {
        std::ostringstream os;
        os << path << ":" << line_no << ": not a number: " << Quoted(token);
        return Status::Error(os.str());
      }
      values.push_back(v);
    }
    if (values.size() != 3 && values.size() != 6) {
      std::ostringstream os;
      os << path << ":" << line_no << ": expected 'x y z' or 'x y z nx ny nz', got "
         << values.size() << " values";
      return Status::Error(os.str());
    }
    if (columns < 0) columns = static_cast<int>(values.size());
    if (static_cast<int>(values.size()) != columns) {
      std::ostringstream os;
      os << path << ":" << line_no << ": " << values.size() << " values where earlier lines had "
         << columns;
      return Status::Error(os.str());
    }
    pts.insert(pts.end(), values.begin(), values.begin() + 3);
    if (columns == 6) nrm.insert(nrm.end(), values.begin() + 3, values.end());
  }
  *cloud = RawCloud();
  cloud->xyz = std::move(pts);
  cloud->normals = std::move(nrm);
  return Status::Ok();
}

}  // namespace internal
}  // namespace femreg
