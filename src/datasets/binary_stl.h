// The binary STL bytes of a triangle surface, for the rigid tools the generators write beside
// their scenes as collision obstacles (a scene's mesh obstacle names a file).
#ifndef FEMREG_DATASETS_BINARY_STL_H_
#define FEMREG_DATASETS_BINARY_STL_H_

#include <cstdint>
#include <string>

#include "femreg/mesh.h"

namespace femreg {
namespace datasets_internal {

// An 80-byte blank header, the triangle count, and per triangle a zero normal (readers take
// the corners' order), its corners as floats and a zero attribute word.
inline std::string BinaryStl(const Vertices& vertices, const Triangles& triangles) {
  std::string stl(80, '\0');
  const uint32_t count = static_cast<uint32_t>(triangles.rows());
  stl.append(reinterpret_cast<const char*>(&count), 4);
  for (int f = 0; f < triangles.rows(); ++f) {
    float rec[12] = {0};
    for (int c = 0; c < 3; ++c)
      for (int d = 0; d < 3; ++d) rec[3 + 3 * c + d] = static_cast<float>(vertices(triangles(f, c), d));
    stl.append(reinterpret_cast<const char*>(rec), 48);
    stl.append(2, '\0');
  }
  return stl;
}

}  // namespace datasets_internal
}  // namespace femreg

#endif  // FEMREG_DATASETS_BINARY_STL_H_
