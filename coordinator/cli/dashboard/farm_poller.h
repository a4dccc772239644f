// What `portico dashboard` knows of the farm: one thread polls the
// coordinator as a client (Status, JobDetail, FetchPreview) at a bounded
// rate, and every page viewer reads the same snapshot, so a hundred open
// pages cost the coordinator what one does. Jobs are polled while active
// (once more when they end); a job's cells, log lines and film only while a
// viewer watches it.
#pragma once

#include <nlohmann/json.hpp>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

#include "common/image/linear_image.h"
#include "common/net/client.h"
#include "coordinator/cli/commands.h"

namespace portico::cli {

// A job's film so far, as the coordinator made it small.
struct PreviewFrame {
  LinearImage image;
  float exposure = 1;          // the job's --exposure
  int64_t cameraRaysDone = 0;  // what it holds: a new value, a new image
};

struct PollSettings {
  std::chrono::milliseconds interval{1000};         // Status of the farm and of active jobs
  std::chrono::milliseconds previewInterval{2000};  // a watched job's cells, log and film, at most this often
  uint32_t previewSide = 640;                       // pixels on the preview's longer side
  size_t listedJobs = 50;                           // the newest jobs, in the list
  size_t polledJobs = 16;                           // active jobs polled each round, newest first
};

class FarmPoller {
 public:
  FarmPoller(ConnectOptions connect, PollSettings settings);
  ~FarmPoller();   // stops polling
  FarmPoller(const FarmPoller&) = delete;
  FarmPoller& operator=(const FarmPoller&) = delete;

  // Blocks until the snapshot is newer than `seen`, `timeout` passes or the
  // poller stops; returns the snapshot's version.
  uint64_t waitForChange(uint64_t seen, std::chrono::milliseconds timeout);
  // {"version", "coordinator", "error", "jobs": [summaries], "workers": [...]}
  // and, for `job`, "job": {"status", "detail", "preview"} (null until polled).
  nlohmann::json snapshot(std::optional<uint64_t> job);
  std::optional<PreviewFrame> preview(uint64_t job);
  // A viewer's interest: watched jobs get their detail and preview polled.
  void watch(uint64_t job);
  void unwatch(uint64_t job);
  void stop();
  bool stopping() const { return stopping_; }

 private:
  // A counter's growth per second over the last kRateWindow of polls:
  // a render lease can take longer than one poll interval.
  struct Rate {
    std::deque<std::pair<std::chrono::steady_clock::time_point, int64_t>> samples;
    double update(int64_t value, std::chrono::steady_clock::time_point when);
  };
  void run();
  void pollRound(net::CoordinatorClient& client);
  // Rates are sampled at `now`, the round's time: a rate not sampled in a round is dropped.
  nlohmann::json summary(const nlohmann::json& status, std::chrono::steady_clock::time_point now);

  ConnectOptions connect_;
  PollSettings settings_;
  std::atomic<bool> stopping_{false};
  std::mutex mutex_;
  std::condition_variable changed_;
  uint64_t version_ = 0;
  std::string error_;
  nlohmann::json farm_;                                  // Status of job 0: jobs and workers
  std::map<uint64_t, nlohmann::json> statuses_;         // Status of each listed job
  std::map<uint64_t, nlohmann::json> details_;          // JobDetail of watched jobs
  std::map<uint64_t, PreviewFrame> previews_;
  std::map<uint64_t, std::chrono::steady_clock::time_point> detailPolled_;
  std::map<uint64_t, int> watchers_;
  std::map<std::string, Rate> rates_;                   // by "job N photons", "worker NAME leases", ...
  std::thread thread_;
};

}  // namespace portico::cli
