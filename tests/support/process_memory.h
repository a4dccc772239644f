// Peak resident memory of a live process, for tests that hold a worker to
// its --memory budget.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>

namespace portico::testing_support {

// VmHWM from /proc/PID/status, in bytes; 0 when the process is gone.
inline uint64_t peakResidentBytes(pid_t pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmHWM:", 0) == 0) {
      std::istringstream in(line.substr(6));
      uint64_t kib = 0;
      in >> kib;
      return kib * 1024;
    }
  return 0;
}

}  // namespace portico::testing_support
