// Wall time for the stage timers of frames, solves and commands (steady: never jumps).
#ifndef FEMREG_PARALLEL_STOPWATCH_H_
#define FEMREG_PARALLEL_STOPWATCH_H_

#include <chrono>

namespace femreg {

// Seconds since `since`.
inline double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

}  // namespace femreg

#endif  // FEMREG_PARALLEL_STOPWATCH_H_
