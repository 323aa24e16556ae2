// A .npy file's bytes, built by hand for the readers' tests: the header dict as given (so a
// test can write a bad one), padded as numpy.save pads it, then the data.
#ifndef FEMREG_TESTS_NPY_BYTES_H_
#define FEMREG_TESTS_NPY_BYTES_H_

#include <string>

namespace femreg {
namespace testing_util {

// Magic, version `major`.0, the header length (2 bytes little-endian in version 1, 4 from
// version 2), `dict` padded with spaces and ended by '\n' so that the data starts at a
// multiple of 64 bytes, then `data`.
inline std::string NpyBytes(const std::string& dict, const std::string& data, int major = 1) {
  const size_t prefix = major >= 2 ? 12 : 10;
  std::string header = dict;
  while ((prefix + header.size() + 1) % 64 != 0) header += ' ';
  header += '\n';
  std::string out = "\x93NUMPY";
  out += static_cast<char>(major);
  out += '\0';
  const size_t n = header.size();
  for (size_t k = 0; k < prefix - 8; ++k) out += static_cast<char>((n >> (8 * k)) & 0xff);
  return out + header + data;
}

}  // namespace testing_util
}  // namespace femreg

#endif  // FEMREG_TESTS_NPY_BYTES_H_
