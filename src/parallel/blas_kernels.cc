#include "femreg/blas_kernels.h"

#include <dlfcn.h>

#include <cstdlib>
#include <cstring>
#include <mutex>

#include "parallel/blas_choice.h"

namespace femreg {
namespace {

using CoreName = char* (*)();
using Hook = void (*)();

CoreName OpenBlasCoreName() {
  return reinterpret_cast<CoreName>(dlsym(RTLD_DEFAULT, "openblas_get_corename"));
}

// The instruction-set level of a set of OpenBLAS kernels: 0 for SSE3 or older, 1 AVX, 2 AVX2
// and FMA, 3 AVX-512; -1 for a name not listed here (then nothing is changed).
int KernelLevel(const char* name) {
  static const char* const kLevel0[] = {"Katmai", "Coppermine", "Northwood", "Prescott", "Banias",
                                        "Atom", "Core2", "Penryn", "Dunnington", "Nehalem",
                                        "Athlon", "Opteron", "Opteron_SSE3", "Barcelona", "Nano",
                                        "Bobcat"};
  for (const char* n : kLevel0) {
    if (std::strcmp(name, n) == 0) return 0;
  }
  if (std::strcmp(name, "Sandybridge") == 0) return 1;
  if (std::strcmp(name, "Haswell") == 0 || std::strcmp(name, "Zen") == 0) return 2;
  if (std::strcmp(name, "SkylakeX") == 0 || std::strcmp(name, "Cooperlake") == 0 ||
      std::strcmp(name, "SapphireRapids") == 0) {
    return 3;
  }
  return -1;
}

// The same level for this CPU (libgcc's checks include the operating system's support of the
// wider registers).
int CpuLevel() {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512cd") &&
      __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512dq") &&
      __builtin_cpu_supports("avx512vl")) {
    return 3;
  }
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return 2;
  if (__builtin_cpu_supports("avx")) return 1;
#endif
  return 0;
}

}  // namespace

std::string BlasCoreName() {
  const CoreName name = OpenBlasCoreName();
  if (name == nullptr) return "";
  const char* s = name();
  return s != nullptr ? std::string(s) : std::string();
}

const char* ChooseBlasKernels(const char* current, int cpu_level,
                              const std::function<bool(const char* table)>& has_table) {
  // Only OpenBLAS's generic kernels are replaced: kernels it chose for an instruction set of
  // their own are its tuned choice (a Zen, a Sandy Bridge), left as they are.
  if (current == nullptr || KernelLevel(current) != 0) return nullptr;
  // OpenBLAS's names for its kernels and the symbols of their tables (present only where the
  // library was built with them), best first.
  struct Kernels {
    int level;
    const char* name;
    const char* table;
  };
  static const Kernels kChoices[] = {{3, "SkylakeX", "gotoblas_SKYLAKEX"},
                                     {2, "Haswell", "gotoblas_HASWELL"},
                                     {1, "Sandybridge", "gotoblas_SANDYBRIDGE"}};
  for (const Kernels& k : kChoices) {
    if (k.level <= cpu_level && has_table(k.table)) return k.name;
  }
  return nullptr;
}

const char* BetterBlasCoreType() {
  if (std::getenv("OPENBLAS_CORETYPE") != nullptr) return nullptr;
  const std::string current = BlasCoreName();
  if (current.empty()) return nullptr;
  return ChooseBlasKernels(current.c_str(), CpuLevel(),
                           [](const char* table) { return dlsym(RTLD_DEFAULT, table) != nullptr; });
}

std::string BlasLibraryPath() {
  const CoreName name = OpenBlasCoreName();
  Dl_info info;
  if (name == nullptr || dladdr(reinterpret_cast<void*>(name), &info) == 0 || info.dli_fname == nullptr) {
    return "";
  }
  return info.dli_fname;
}

std::string UseBetterBlasKernels() {
  static std::mutex mutex;
  const std::lock_guard<std::mutex> lock(mutex);
  const char* better = BetterBlasCoreType();
  const Hook quit = reinterpret_cast<Hook>(dlsym(RTLD_DEFAULT, "gotoblas_dynamic_quit"));
  const Hook init = reinterpret_cast<Hook>(dlsym(RTLD_DEFAULT, "gotoblas_dynamic_init"));
  if (better == nullptr || quit == nullptr || init == nullptr) return BlasCoreName();
  // OpenBLAS chooses its kernels in gotoblas_dynamic_init (run as it loads), from
  // OPENBLAS_CORETYPE when set: the same choice again, with the variable set. The variable
  // stays set, so that programs this one starts choose the same.
  if (setenv("OPENBLAS_CORETYPE", better, 1) != 0) return BlasCoreName();
  quit();
  init();
  return BlasCoreName();
}

}  // namespace femreg
