#include "parallel/signals.h"

namespace femreg {

KeepSignalHandlers::KeepSignalHandlers() {
  saved_ = sigaction(SIGTERM, nullptr, &term_) == 0 && sigaction(SIGABRT, nullptr, &abrt_) == 0;
}

KeepSignalHandlers::~KeepSignalHandlers() {
  if (!saved_) return;
  sigaction(SIGTERM, &term_, nullptr);
  sigaction(SIGABRT, &abrt_, nullptr);
}

}  // namespace femreg
