// `portico render` as a child process, and its statistics read back: the one
// measurement of the pipeline benches (pipeline_run.h).
#include "coordinator/cli/bench/pipeline_run.h"

#include <fmt/format.h>
#include <sys/resource.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <thread>

#include "common/util/child_process.h"
#include "coordinator/cli/bench/accel_measure.h"

namespace portico::cli {

double cpuSeconds(int who) {
  rusage usage{};
  getrusage(who, &usage);
  const auto seconds = [](const timeval& t) { return double(t.tv_sec) + double(t.tv_usec) * 1e-6; };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

std::string loadAverage() {
  std::ifstream in("/proc/loadavg");
  std::string first;
  return in >> first ? first : "?";
}

int64_t jsonInt(const nlohmann::json& j, const char* section, const char* key) {
  if (!j.contains(section) || !j[section].contains(key)) return 0;
  return j[section][key].get<int64_t>();
}

namespace {

std::string readWholeFile(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::vector<std::string> renderArguments(const PipelineRunSpec& spec, const std::string& output) {
  const std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
  std::vector<std::string> arguments{self, "render", spec.store, "-o", output,
                                     "--workers", std::to_string(spec.workers),
                                     "--photons", std::to_string(spec.photons),
                                     "--seed", std::to_string(spec.seed),
                                     "--spp", std::to_string(spec.spp), "--gather", std::to_string(spec.gather),
                                     "--width", std::to_string(spec.width), "--height", std::to_string(spec.height),
                                     "--accel", spec.accel, "--memory", spec.memory, "--log-level", "warn"};
  arguments.insert(arguments.end(), spec.moreArguments.begin(), spec.moreArguments.end());
  return arguments;
}

// Waits for the child, stopping it (and failing the run) at the timeout: a
// job that can never finish must not hold a whole benchmark.
int waitWithTimeout(ChildProcess& child, double timeoutSeconds, bool& timedOut) {
  timedOut = false;
  if (timeoutSeconds <= 0) return child.wait();
  const auto start = Clock::now();
  while (child.running()) {
    if (secondsSince(start) > timeoutSeconds) {
      timedOut = true;
      return child.stop();
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return child.exitCode();
}

}  // namespace

PipelineRunStats parsePipelineStatistics(const nlohmann::json& stats) {
  PipelineRunStats s;
  s.photonSeconds = double(jsonInt(stats, "time_ms", "photons")) / 1e3;
  s.renderSeconds = double(jsonInt(stats, "time_ms", "render")) / 1e3;
  s.buildSeconds = double(jsonInt(stats, "time_ms", "accelerator_build")) / 1e3;
  s.emitted = jsonInt(stats, "photons", "emitted");
  s.deposits = jsonInt(stats, "photons", "deposits");
  s.absorbed = jsonInt(stats, "photons", "absorbed");
  s.escaped = jsonInt(stats, "photons", "escaped");
  s.crossings = jsonInt(stats, "photons", "crossings");
  s.portalCopies = jsonInt(stats, "photons", "portal_copies");
  s.raysTraced = jsonInt(stats, "rays", "traced");
  s.rayCrossings = jsonInt(stats, "rays", "crossings");
  s.cameraRays = jsonInt(stats, "rays", "camera");
  s.shadowRays = jsonInt(stats, "rays", "shadow");
  s.gatherRays = jsonInt(stats, "rays", "gather");
  s.cellsLoaded = jsonInt(stats, "cells", "loaded");
  s.cacheHits = jsonInt(stats, "cells", "cache_hits");
  s.bytesRead = jsonInt(stats, "cells", "bytes_read");
  s.leases = stats.contains("leases") ? stats["leases"].get<int64_t>() : 0;
  if (stats.contains("accelerators") && stats["accelerators"].is_object())
    for (const auto& [spec, cells] : stats["accelerators"].items())
      if (cells.is_number_integer()) s.accelerators[spec] = cells.get<int64_t>();
  return s;
}

PipelineRunStats runPipeline(const PipelineRunSpec& spec, const std::filesystem::path& work, const std::string& tag) {
  const std::filesystem::path output = work / (tag + ".exr");
  const std::filesystem::path log = work / (tag + ".log");
  const std::string statisticsPath = output.string() + ".json";
  const auto start = Clock::now();
  const double cpuStart = cpuSeconds(RUSAGE_CHILDREN);
  ChildProcess child(renderArguments(spec, output.string()), log.string());
  bool timedOut = false;
  const int status = waitWithTimeout(child, spec.timeoutSeconds, timedOut);
  const double wall = secondsSince(start), cpu = cpuSeconds(RUSAGE_CHILDREN) - cpuStart;
  const auto cleanUp = [&] {
    std::error_code ignored;
    for (const auto& path : {output, std::filesystem::path(statisticsPath), log}) std::filesystem::remove(path, ignored);
  };
  if (status != 0 || timedOut) {
    std::string text = readWholeFile(log);
    cleanUp();
    const std::string why = timedOut ? fmt::format("stopped after {:.0f} s", spec.timeoutSeconds)
                                     : fmt::format("status {}", status);
    throw PipelineRunError(fmt::format("portico render --accel {} with {} worker(s) failed ({}); its output ({}):\n{}",
                                       spec.accel, spec.workers, why, log.string(), text),
                           text, status);
  }
  std::ifstream in(statisticsPath);
  if (!in) {
    cleanUp();
    throw std::runtime_error("portico render wrote no statistics at " + statisticsPath);
  }
  PipelineRunStats stats = parsePipelineStatistics(nlohmann::json::parse(in));
  stats.wallSeconds = wall;
  stats.cpuSeconds = cpu;
  if (!spec.keepImage.empty()) std::filesystem::rename(output, spec.keepImage);
  cleanUp();
  return stats;
}

}  // namespace portico::cli
