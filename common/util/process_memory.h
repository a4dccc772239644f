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

}  // namespace portico
