// This process's memory and CPU time as the kernel counts them, for the
// job statistics: a budget is only kept if it is measured.
#pragma once

#include <cstdint>

namespace portico {

// The most resident memory this process has had since it started (VmHWM),
// in bytes; 0 where /proc cannot tell.
uint64_t peakResidentBytes();

// CPU time this process has used since it started, user and system, in
// microseconds (getrusage).
int64_t processCpuMicros();

// The calling thread's CPU time and its time spent runnable but waiting for
// a core (the run queue), in microseconds, from /proc/thread-self/schedstat;
// runQueueMicros is -1 where the kernel does not keep it (then cpuMicros
// comes from CLOCK_THREAD_CPUTIME_ID). A lease's wall time less the two is
// what it spent blocked (reads, page faults): the cluster model tells a
// lease's own cost from what sharing the cores with other processes added.
struct ThreadTimes {
  int64_t cpuMicros = 0;
  int64_t runQueueMicros = -1;
};
ThreadTimes threadTimes();

}  // namespace portico
