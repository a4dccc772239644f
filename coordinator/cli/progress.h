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

// The wait before the next status poll of a job: statusPollInterval, cut
// short where the render phase's pace says the job ends sooner (a poll that
// comes long after the end adds to the run: at 3.5 s into a small render,
// the interval is 350 ms). The pace is the camera rays done since they were
// first seen, over the time since; the cut wait is at least a quarter of
// the interval and 50 ms, so a wrong guess costs at most four times the
// polls.
class PollPacer {
 public:
  using Clock = std::chrono::steady_clock;
  explicit PollPacer(Clock::time_point started) : started_(started) {}
  std::chrono::milliseconds next(const nlohmann::json& status, Clock::time_point now);

 private:
  Clock::time_point started_;
  Clock::time_point firstRaysSeen_{};
  int64_t firstRays_ = 0;   // camera rays done at firstRaysSeen_; 0 while none seen
};

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
