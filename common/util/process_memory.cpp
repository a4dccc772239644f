#include "common/util/process_memory.h"

#include <sys/resource.h>

#include <cstdio>
#include <cstring>

namespace portico {

uint64_t peakResidentBytes() {
  // stdio rather than a stream: a worker reads it once per Result.
  std::FILE* status = std::fopen("/proc/self/status", "r");
  if (!status) return 0;
  char line[256];
  unsigned long long kib = 0;
  while (std::fgets(line, sizeof line, status))
    if (std::strncmp(line, "VmHWM:", 6) == 0) {
      std::sscanf(line + 6, "%llu", &kib);
      break;
    }
  std::fclose(status);
  return uint64_t(kib) * 1024;
}

int64_t processCpuMicros() {
  rusage usage{};
  if (::getrusage(RUSAGE_SELF, &usage) != 0) return 0;
  const auto micros = [](const timeval& t) { return int64_t(t.tv_sec) * 1000000 + t.tv_usec; };
  return micros(usage.ru_utime) + micros(usage.ru_stime);
}

}  // namespace portico
