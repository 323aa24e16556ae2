// femreg/version.h - the version of the femreg library.
#ifndef FEMREG_VERSION_H_
#define FEMREG_VERSION_H_

namespace femreg {

// The library's version, "MAJOR.MINOR.PATCH". It is written in one place, the
// project(femreg VERSION ...) line of CMakeLists.txt; `femreg --version`, summary.json's
// femreg_version, Python's femreg.__version__ and the wheel's metadata all report it.
const char* Version();

}  // namespace femreg

#endif  // FEMREG_VERSION_H_
