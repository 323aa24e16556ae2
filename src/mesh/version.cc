#include "femreg/version.h"

// CMakeLists.txt defines FEMREG_VERSION for this file alone, from project(VERSION).
#ifndef FEMREG_VERSION
#error "FEMREG_VERSION must be defined (CMakeLists.txt sets it from the project's version)"
#endif

namespace femreg {

const char* Version() { return FEMREG_VERSION; }

}  // namespace femreg
