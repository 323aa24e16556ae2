// The BLAS kernels under the sparse factorizations. OpenBLAS (built for many CPUs) picks its
// kernels by the CPU's model number, and takes its generic SSE3 ones for a model newer than
// itself: Debian 12's OpenBLAS 0.3.21 on a 2023 Xeon runs the factorizations' dense products
// several times slower than it could (docs/guide/busy-machines.md#blas-kernels-on-new-cpus).
// These functions find that case and fix it. The `femreg` command and the Python package do
// it by themselves; a C++ program that links libfemreg can call UseBetterBlasKernels() at
// the start of main(), or set OPENBLAS_CORETYPE in its environment.
#ifndef FEMREG_BLAS_KERNELS_H_
#define FEMREG_BLAS_KERNELS_H_

#include <string>

namespace femreg {

// The kernels the loaded OpenBLAS uses ("Prescott", "Haswell", "SkylakeX", ...); "" when the
// BLAS is not OpenBLAS.
std::string BlasCoreName();

// The file of the loaded OpenBLAS ("" when the BLAS is not OpenBLAS).
std::string BlasLibraryPath();

// OpenBLAS's name for the best kernels this CPU and operating system support ("SkylakeX" with
// AVX-512, "Haswell" with AVX2 and FMA, "Sandybridge" with AVX), where the loaded OpenBLAS
// took its generic (SSE3 or older) kernels and has those built in. nullptr otherwise: another
// BLAS, kernels OpenBLAS chose for the CPU (left as they are), or OPENBLAS_CORETYPE set by the
// user.
const char* BetterBlasCoreType();

// Switches the loaded OpenBLAS to BetterBlasCoreType()'s kernels, in this process, and
// returns the kernels in use afterwards (BlasCoreName()). Call it before any other thread
// uses the BLAS (at the start of main()): the switch is not safe against a BLAS call in
// flight. Does nothing where BetterBlasCoreType() is nullptr.
std::string UseBetterBlasKernels();

}  // namespace femreg

#endif  // FEMREG_BLAS_KERNELS_H_
