// The process's resident set size, from /proc/self/statm.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <fstream>

namespace portico {

inline uint64_t residentBytes() {
  std::ifstream statm("/proc/self/statm");
  uint64_t size = 0, resident = 0;
  statm >> size >> resident;
  return resident * uint64_t(::sysconf(_SC_PAGESIZE));
}

}  // namespace portico
