// The rule of BetterBlasCoreType (femreg/blas_kernels.h) on its inputs, for the tests: which
// kernels replace OpenBLAS's `current` ones on a CPU of instruction-set level `cpu_level` (0
// SSE3 or older, 1 AVX, 2 AVX2 and FMA, 3 AVX-512), given which kernel tables the library has.
#ifndef FEMREG_PARALLEL_BLAS_CHOICE_H_
#define FEMREG_PARALLEL_BLAS_CHOICE_H_

#include <functional>

namespace femreg {

// OpenBLAS's name for the replacement, or nullptr to leave `current` as it is. `has_table`
// says whether the library has a kernel table (its symbol, e.g. "gotoblas_HASWELL").
const char* ChooseBlasKernels(const char* current, int cpu_level,
                              const std::function<bool(const char* table)>& has_table);

}  // namespace femreg

#endif  // FEMREG_PARALLEL_BLAS_CHOICE_H_
