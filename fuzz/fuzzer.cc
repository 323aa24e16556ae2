// A libFuzzer target: FEMREG_FUZZ_TARGET names the format (fuzz/CMakeLists.txt builds this
// file once per format). See fuzz/fuzz_inputs.h for what each target checks.
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_inputs.h"

#ifndef FEMREG_FUZZ_TARGET
#error "FEMREG_FUZZ_TARGET must name the format"
#endif

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  femreg::fuzz::RunInput(FEMREG_FUZZ_TARGET, data, size);
  return 0;
}
