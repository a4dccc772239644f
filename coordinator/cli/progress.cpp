#include "coordinator/cli/progress.h"

#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <iostream>

namespace portico::cli {

namespace {
// Counts are read with a 64-bit default: nlohmann's value() returns the
// default's type, and photon, ray and byte counts of a large job pass 2^31.

int64_t steadyMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// "  pass 3/64 error 1.24 %" for a job rendered in passes; "" for one pass.
std::string passesText(const nlohmann::json& s) {
  if (!s.contains("render_passes")) return "";
  const auto& passes = s["render_passes"];
  const uint32_t most = passes.value("max_passes", 1u);
  if (most <= 1) return "";
  const auto& current = passes["current"];
  const uint32_t pass = current.is_number() ? current.get<uint32_t>() : passes.value("done", 0u);
  if (pass == 0) return "";   // still in the photon pass
  const auto& estimate = passes["error_estimate"];
  std::string text = fmt::format("  pass {}/{} error {}", pass, most,
                                 estimate.is_number() ? fmt::format("{:.2f} %", 100 * estimate.get<double>()) : "-");
  if (passes["stopped"].is_string()) text += fmt::format(" ({})", passes["stopped"].get<std::string>());
  return text;
}

// A line of `portico status` for a job rendered in passes: the estimate after each.
std::string passesDescription(const nlohmann::json& s) {
  if (!s.contains("render_passes") || s["render_passes"].value("max_passes", 1u) <= 1) return "";
  const auto& passes = s["render_passes"];
  std::string text = fmt::format("render passes: {} done (at most {}), error after each:", passes.value("done", 0u),
                                 passes.value("max_passes", 1u));
  for (const auto& estimate : passes["error_estimates"])
    text += estimate.is_number() ? fmt::format(" {:.2f} %", 100 * estimate.get<double>()) : std::string(" -");
  if (passes["stopped"].is_string()) text += fmt::format("; stopped: {}", passes["stopped"].get<std::string>());
  return text + "\n";
}

// " tags a b" from a status's list `key` (prefix and names); "" when it is empty or absent.
std::string tagsText(const nlohmann::json& s, const char* key, std::string_view prefix) {
  if (!s.contains(key) || !s[key].is_array() || s[key].empty()) return "";
  std::string text(prefix);
  for (size_t i = 0; i < s[key].size(); ++i) text += (i ? " " : "") + s[key][i].get<std::string>();
  return text;
}

std::string summaryLine(const nlohmann::json& s) {
  const auto& p = s["progress"];
  std::string line = fmt::format("job {} {:8} photons {}/{}  camera rays {}/{}  {:.2f} Mrays/s",
                                 s.value("job", int64_t{0}), s.value("state", "?"), p.value("photons_done", int64_t{0}),
                                 p.value("photons_total", int64_t{0}), p.value("camera_rays_done", int64_t{0}),
                                 p.value("camera_rays_total", int64_t{0}), s.value("rays_per_s", 0.0) / 1e6);
  if (s.contains("eta_s")) line += fmt::format("  ETA {:.0f} s", s["eta_s"].get<double>());
  if (s.contains("waiting") && !s["waiting"].empty()) line += "  waiting: " + s["waiting"][0].get<std::string>();
  return line + passesText(s);
}
}  // namespace

std::chrono::milliseconds PollPacer::next(const nlohmann::json& status, Clock::time_point now) {
  const std::chrono::milliseconds interval = statusPollInterval(now - started_);
  const auto& progress = status.find("progress");
  if (progress == status.end() || !progress->is_object()) return interval;
  const int64_t done = progress->value("camera_rays_done", int64_t{0});
  const int64_t total = progress->value("camera_rays_total", int64_t{0});
  if (firstRays_ == 0) {
    if (done > 0) firstRays_ = done, firstRaysSeen_ = now;
    return interval;
  }
  if (done <= firstRays_ || done >= total) return interval;
  const double seconds = std::chrono::duration<double>(now - firstRaysSeen_).count();
  const auto remaining = std::chrono::milliseconds(
      static_cast<int64_t>(1000.0 * seconds * double(total - done) / double(done - firstRays_)));
  const auto shortest = std::max(interval / 4, std::chrono::milliseconds(50));
  return std::clamp(remaining, shortest, interval);
}

std::string describeStatus(const nlohmann::json& s) {
  std::string text;
  if (s.contains("jobs")) {
    for (const auto& job : s["jobs"])
      text += fmt::format("job {} {} priority {}{}{}{}\n", job.value("job", int64_t{0}), job.value("state", "?"),
                          job.value("priority", 0), tagsText(job, "required_tags", ", requires tags "),
                          job.value("mine", true) ? "" : ", another user's",
                          job.value("error", "").empty() ? "" : " — " + job.value("error", ""));
    if (s["jobs"].empty()) text += "no jobs\n";
  } else {
    text += summaryLine(s) + "\n";
    text += fmt::format("priority: {}{}\n", s.value("priority", 0), tagsText(s, "required_tags", "; requires tags "));
    if (!s.value("mine", true)) text += "another user's job: its paths, error and log are not shown\n";
    if (s.contains("error")) text += fmt::format("error: {}\n", s.value("error", ""));
    if (s.contains("waiting"))
      for (const auto& reason : s["waiting"]) text += fmt::format("waiting: {}\n", reason.get<std::string>());
    const auto& photons = s["photons"];
    text += fmt::format("photons: emitted {} deposited {} absorbed {} escaped {} queued {}\n",
                        photons.value("emitted", int64_t{0}), photons.value("deposits", int64_t{0}), photons.value("absorbed", int64_t{0}),
                        photons.value("escaped", int64_t{0}), photons.value("queued", int64_t{0}));
    if (s.contains("photon_pass") && s["photon_pass"]["reused_from_job"].is_number())
      text += fmt::format("photon pass: job {}'s, reused\n", s["photon_pass"]["reused_from_job"].get<uint64_t>());
    text += fmt::format("rays: traced {} crossings {} ({:.3f} per camera ray)\n", s["rays"].value("traced", int64_t{0}),
                        s["rays"].value("crossings", int64_t{0}), s["rays"].value("crossings_per_camera_ray", 0.0));
    text += fmt::format("cells: loaded {} ({} distinct, {} reloads) cache hits {} bytes read {}\n",
                        s["cells"].value("loaded", int64_t{0}), s["cells"].value("distinct_loaded", int64_t{0}),
                        s["cells"].value("reloads", int64_t{0}), s["cells"].value("cache_hits", int64_t{0}),
                        s["cells"].value("bytes_read", int64_t{0}));
    if (s.contains("memory")) {
      const auto& memory = s["memory"];
      text += fmt::format("memory: coordinator peak {:.1f} MiB", memory.value("coordinator_peak_rss_bytes", int64_t{0}) / 1048576.0);
      for (const auto& [name, w] : memory["workers"].items())
        text += fmt::format(", {} peak {:.1f} MiB of {:.1f}", name, w.value("peak_rss_bytes", int64_t{0}) / 1048576.0,
                            w.value("budget_bytes", int64_t{0}) / 1048576.0);
      text += "\n";
    }
    if (s.contains("disk"))
      text += fmt::format("disk: job's files {:.1f} MiB (photons {:.1f}, queued rays {:.1f}), jobs.db {:.1f} MiB\n",
                          s["disk"].value("job_bytes", int64_t{0}) / 1048576.0, s["disk"].value("photon_file_bytes", int64_t{0}) / 1048576.0,
                          s["disk"].value("batch_file_bytes", int64_t{0}) / 1048576.0,
                          s["disk"].value("jobs_db_bytes", int64_t{0}) / 1048576.0);
    text += passesDescription(s);
    if (!s["pending_cells"].empty()) {
      text += "pending work by cell:";
      for (const auto& c : s["pending_cells"]) text += fmt::format(" {}:{}", c.value("cell", int64_t{0}), c.value("work", int64_t{0}));
      text += "\n";
    }
  }
  if (s.contains("workers")) {
    text += fmt::format("workers: {}\n", s["workers"].size());
    for (const auto& w : s["workers"]) {
      const bool stalled = w.contains("stalled");
      text += fmt::format("  {}{} {} ({} leases), holds {} cells, recent:", w.value("name", "?"), tagsText(w, "tags", " tags "),
                          stalled ? "stalled" : w.value("idle", false) ? "idle" : "busy", w.value("leases", int64_t{0}),
                          w.value("cells_held", int64_t{0}));
      for (const auto& c : w["cells"]) text += fmt::format(" {}", c.value("cell", int64_t{0}));
      if (stalled) text += fmt::format("; its leases were taken back: {}", w.value("stalled", ""));
      if (const int64_t refused = w.value("refused_results", int64_t{0}); refused > 0)
        text += fmt::format("; {} of its Results refused", refused);
      text += "\n";
    }
  }
  return text;
}

ProgressDisplay::ProgressDisplay(bool quiet) : quiet_(quiet), terminal_(isatty(STDERR_FILENO)) {}

void ProgressDisplay::update(const nlohmann::json& s) {
  if (quiet_) return;
  const double fraction = s["progress"].value("fraction", 0.0);
  if (terminal_) {
    const int width = 30;
    const int filled = static_cast<int>(fraction * width + 0.5);
    std::string bar(filled, '#');
    bar.resize(width, '.');
    std::fprintf(stderr, "\r[%s] %3.0f%% %s\033[K", bar.c_str(), fraction * 100, summaryLine(s).c_str());
    std::fflush(stderr);
    return;
  }
  const int64_t now = steadyMs();
  // A line per state, and per render pass of a job rendered in passes.
  const std::string state = s.value("state", "") + passesText(s);
  if (now - lastLineMs_ >= 5000 || state != lastState_) {
    lastLineMs_ = now;
    lastState_ = state;
    std::cerr << fmt::format("{:3.0f}% {}\n", fraction * 100, summaryLine(s));
  }
}

void ProgressDisplay::finish(const nlohmann::json& s) {
  if (terminal_ && !quiet_) std::fprintf(stderr, "\n");
  const std::string state = s.value("state", "?");
  const std::string error = s.value("error", "");
  const int64_t job = s.value("job", int64_t{0});
  // elapsed_s of an ended job: from its submit to its end.
  if (state == "done" && error.empty()) {
    if (!quiet_)
      std::cerr << fmt::format("job {} done in {:.1f} s: {}{}\n", job, s.value("elapsed_s", 0.0),
                               s["settings"].value("output", ""), passesText(s));
    return;
  }
  // What makes the command fail is said even with --quiet.
  if (state == "done")
    std::cerr << fmt::format("job {} done in {:.1f} s, but {}\n", job, s.value("elapsed_s", 0.0), error);
  else
    std::cerr << fmt::format("job {} {}: {}\n", job, state, error);
}

}  // namespace portico::cli
