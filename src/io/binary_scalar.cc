#include <cstdint>
#include <cstring>

#include "io/io_internal.h"

namespace femreg {
namespace internal {

double DecodeBinaryScalar(const char* p, const BinaryScalar& type, bool big_endian) {
  uint64_t bits = 0;
  for (int i = 0; i < type.size; ++i) {
    const int k = big_endian ? i : type.size - 1 - i;
    bits = (bits << 8) | static_cast<unsigned char>(p[k]);
  }
  if (type.is_float) {
    if (type.size == 4) {
      const uint32_t b32 = static_cast<uint32_t>(bits);
      float f;
      std::memcpy(&f, &b32, 4);
      return f;
    }
    double d;
    std::memcpy(&d, &bits, 8);
    return d;
  }
  if (!type.is_signed) return static_cast<double>(bits);
  const int shift = 64 - 8 * type.size;
  return static_cast<double>(static_cast<int64_t>(bits << shift) >> shift);  // sign-extend
}

}  // namespace internal
}  // namespace femreg
