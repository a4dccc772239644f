// The coordinator's recent log lines about each job, for `portico
// dashboard` (JobDetailRequest): an spdlog sink that keeps the lines naming
// "job N" (submitted, leases requeued, passes, failures, cancelled), the
// last kLinesPerJob of each of the last kJobs jobs. The log itself (stderr,
// journald) stays the complete record.
#pragma once

#include <spdlog/sinks/base_sink.h>

#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace portico {

class JobLog : public spdlog::sinks::base_sink<std::mutex> {
 public:
  static constexpr size_t kLinesPerJob = 200;
  static constexpr size_t kJobs = 256;

  // The kept lines of `job`, oldest first.
  std::vector<std::string> lines(uint64_t job);

 protected:
  void sink_it_(const spdlog::details::log_msg& message) override;
  void flush_() override {}

 private:
  std::map<uint64_t, std::deque<std::string>> lines_;
};

}  // namespace portico
