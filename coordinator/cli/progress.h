// Progress of a job for people: a live bar on a terminal, plain lines in a
// log, and a one-screen description for `portico status`.
#pragma once

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <string>

namespace portico::cli {

std::string describeStatus(const nlohmann::json& status);

// A job's state as status reports it: done, failed or cancelled (no more work).
inline bool jobEnded(const std::string& state) { return state == "done" || state == "failed" || state == "cancelled"; }

// How long a command waiting on a job sleeps between status polls, `waited`
// into the wait: 50 ms at first (a small render ends within a second, and
// a longer sleep after it adds to every run), then a tenth of the time
// waited, at most 1 s. Each status reply builds the job's statistics, whose
// cost grows with the building (per-cell load counters): on 101 floors,
// polls every 50 ms cost the coordinator a third of the machine.
inline std::chrono::milliseconds statusPollInterval(std::chrono::steady_clock::duration waited) {
  const auto tenth = std::chrono::duration_cast<std::chrono::milliseconds>(waited) / 10;
  return std::clamp(tenth, std::chrono::milliseconds(50), std::chrono::milliseconds(1000));
}

class ProgressDisplay {
 public:
  explicit ProgressDisplay(bool quiet);
  void update(const nlohmann::json& status);
  void finish(const nlohmann::json& status);

 private:
  bool quiet_;
  bool terminal_;
  int64_t lastLineMs_ = 0;
  std::string lastState_;   // and render pass: a new one gets a line
};

}  // namespace portico::cli
