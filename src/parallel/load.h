// The machine's load as the adaptive thread count reads it (threads.cc's AvailableThreadCount),
// split out so that the count of this process's own threads can be tested.
#ifndef FEMREG_PARALLEL_LOAD_H_
#define FEMREG_PARALLEL_LOAD_H_

namespace femreg {

// The kernel's count of running and runnable threads, system-wide (the fourth field of
// /proc/loadavg, "running/total"); -1 where it cannot be read.
int RunnableThreads();

// This process's threads that are running or runnable (state R in /proc/self/task/*/stat),
// the caller among them; -1 where they cannot be read.
int OwnRunnableThreads();

// The hardware threads other processes leave free: `cores` less the runnable threads that are
// not this process's (`running` system-wide, `own` of them this process's), within [1, cores].
// A worker of femreg's that polls for its next job, or an OpenMP thread that spins before it
// sleeps, is runnable but no other process's load.
int ThreadsLeftFree(int cores, int running, int own);

}  // namespace femreg

#endif  // FEMREG_PARALLEL_LOAD_H_
