#include "common/util/process_memory.h"

#include <sys/resource.h>

#include <ctime>

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

ThreadTimes threadTimes() {
  ThreadTimes times;
  if (std::FILE* schedstat = std::fopen("/proc/thread-self/schedstat", "r")) {
    unsigned long long runNanos = 0, waitNanos = 0;
    if (std::fscanf(schedstat, "%llu %llu", &runNanos, &waitNanos) == 2) {
      times.cpuMicros = int64_t(runNanos / 1000);
      times.runQueueMicros = int64_t(waitNanos / 1000);
    }
    std::fclose(schedstat);
    if (times.runQueueMicros >= 0) return times;
  }
  timespec cpu{};
  if (::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &cpu) == 0)
    times.cpuMicros = int64_t(cpu.tv_sec) * 1000000 + cpu.tv_nsec / 1000;
  return times;
}

}  // namespace portico
