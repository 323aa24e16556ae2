// What femreg's libraries do to the process's signal handlers, undone. METIS (GKlib, under
// CHOLMOD's analysis with the METIS ordering) installs handlers of its own for SIGTERM and
// SIGABRT with signal() while it runs and puts the previous ones back with signal(), with
// System V semantics (SA_RESETHAND | SA_NODEFER): a host's SIGTERM handler (femreg
// register's, a tracker's) then ran once and the next SIGTERM killed the process.
#ifndef FEMREG_PARALLEL_SIGNALS_H_
#define FEMREG_PARALLEL_SIGNALS_H_

#include <csignal>

namespace femreg {

// While alive, nothing; on destruction, SIGTERM's and SIGABRT's dispositions (handler, mask
// and flags) are what they were at construction. Around a call that may run METIS.
class KeepSignalHandlers {
 public:
  KeepSignalHandlers();
  ~KeepSignalHandlers();
  KeepSignalHandlers(const KeepSignalHandlers&) = delete;
  KeepSignalHandlers& operator=(const KeepSignalHandlers&) = delete;

 private:
  struct sigaction term_{}, abrt_{};
  bool saved_ = false;
};

}  // namespace femreg

#endif  // FEMREG_PARALLEL_SIGNALS_H_
