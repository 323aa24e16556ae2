// Runs a function in a forked child with a bounded wait, for the fork-safety tests: a child
// that deadlocks is ended by its alarm, and killed here if it outlives a generous bound, so a
// hang fails the test instead of stalling it.
#ifndef FEMREG_TESTS_FORKED_CHILD_H_
#define FEMREG_TESTS_FORKED_CHILD_H_

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <string>
#include <thread>

namespace femreg {
namespace testing_util {

// Forks; the child exits with body()'s code. The child's exit code (0 and up), or a message
// in *failure (and -1) where it did not exit: fork or waitpid failed, it died of a signal (14:
// its alarm, a hang), or it hung past the bound.
inline int ExitCodeOfForkedChild(int (*body)(), std::string* failure) {
  const pid_t child = fork();
  if (child < 0) {
    *failure = std::string("fork failed: ") + std::strerror(errno);
    return -1;
  }
  if (child == 0) {
    alarm(30);
    _exit(body());
  }
  int status = 0;
  pid_t done = 0;
  for (int waited_ms = 0; waited_ms < 60000 && done == 0; waited_ms += 10) {
    done = waitpid(child, &status, WNOHANG);
    if (done == 0) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (done == 0) {
    kill(child, SIGKILL);
    waitpid(child, &status, 0);
    *failure = "the child hung";
    return -1;
  }
  if (done < 0) {
    *failure = std::string("waitpid failed: ") + std::strerror(errno);
    return -1;
  }
  if (WIFSIGNALED(status)) {
    *failure = "the child died of signal " + std::to_string(WTERMSIG(status)) + " (14: its alarm: a hang)";
    return -1;
  }
  if (!WIFEXITED(status)) {
    *failure = "the child did not exit";
    return -1;
  }
  return WEXITSTATUS(status);
}

}  // namespace testing_util
}  // namespace femreg

#endif  // FEMREG_TESTS_FORKED_CHILD_H_
