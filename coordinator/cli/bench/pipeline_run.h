// One measurement of the real pipeline, shared by `portico bench pipeline`
// and `portico bench paper`: `portico render` run as a child process (its own
// coordinator and workers), and the job statistics JSON it writes beside the
// image read back. Plus the small helpers both benches time with.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace portico::cli {

// (secondsSince and median are accel_measure.h's, shared with `bench accel`.)

// CPU seconds (user + system) used so far by this process (RUSAGE_SELF) or by
// its waited-for descendants (RUSAGE_CHILDREN).
double cpuSeconds(int who);
// The 1-minute load average ("?" where /proc/loadavg cannot be read): a
// shared machine's other work shows up here, and in the timings.
std::string loadAverage();
// j[section][key] as an integer, 0 when absent (older statistics files).
int64_t jsonInt(const nlohmann::json& j, const char* section, const char* key);

// What `portico render` is asked to do. The defaults are the photon-pass-only
// run of the benches: the smallest render a job can have (8x8 pixels, 1 spp,
// no gathering), so that time_ms.photons is what is measured.
struct PipelineRunSpec {
  std::string store;
  uint32_t workers = 2;
  uint64_t photons = 1000000;
  uint64_t seed = 1;
  uint32_t spp = 1, gather = 0, width = 8, height = 8;
  std::string accel = "grid";
  std::string memory = "8GiB";   // per worker
  double timeoutSeconds = 0;     // 0: none; else the child is stopped and the run fails
  std::vector<std::string> moreArguments;   // after the above (--camera NAME, --light-sampler scan, ...)
  std::filesystem::path keepImage;          // non-empty: the image is moved here rather than removed
};

// The statistics of one finished job (job_report.cpp's keys), and the child's cost.
struct PipelineRunStats {
  double photonSeconds = 0;   // time_ms.photons: submission to last photon Result (loads and builds included)
  double renderSeconds = 0;   // time_ms.render
  double buildSeconds = 0;    // time_ms.accelerator_build: every worker's builds added up
  double wallSeconds = 0;     // the child process, start-up and render phase included
  double cpuSeconds = 0;      // the child's CPU time, every thread and process
  int64_t emitted = 0, deposits = 0, absorbed = 0, escaped = 0, crossings = 0, portalCopies = 0;
  int64_t raysTraced = 0, rayCrossings = 0, cameraRays = 0, shadowRays = 0, gatherRays = 0;
  int64_t cellsLoaded = 0, cacheHits = 0, bytesRead = 0, leases = 0;
  // "accelerators": {"<concrete spec>": cells} when the job reports it (`--accel auto`); empty otherwise.
  std::map<std::string, int64_t> accelerators;
};

// A run whose child exited non-zero (or was stopped at its timeout); the
// child's output is kept so that callers can tell why (an unknown --accel, ...).
class PipelineRunError : public std::runtime_error {
 public:
  PipelineRunError(const std::string& message, std::string output, int status)
      : std::runtime_error(message), output_(std::move(output)), status_(status) {}
  const std::string& output() const { return output_; }
  int status() const { return status_; }

 private:
  std::string output_;
  int status_;
};

// Runs `portico render` (this executable) with `spec`, its image, statistics
// and log under `work` named after `tag`, and removes them afterwards.
// Throws PipelineRunError when the child fails, std::runtime_error when it
// wrote no statistics.
PipelineRunStats runPipeline(const PipelineRunSpec& spec, const std::filesystem::path& work, const std::string& tag);

// Reads the fields above from a statistics JSON (`OUT.png.json`).
PipelineRunStats parsePipelineStatistics(const nlohmann::json& stats);

}  // namespace portico::cli
