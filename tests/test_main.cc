// The tests' main: the BLAS kernels the femreg command and the Python package run
// (femreg/blas_kernels.h), so that on a CPU newer than its OpenBLAS a test checks the
// numbers a user gets. (threads_test keeps GoogleTest's own main: it tests the switch.)
#include <gtest/gtest.h>

#include "femreg/blas_kernels.h"

int main(int argc, char** argv) {
  femreg::UseBetterBlasKernels();
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
