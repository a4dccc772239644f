#include "coordinator/cli/bench/bench_analyze.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "common/analysis/sensor.h"
#include "common/scene/store/scene_store.h"
#include "common/util/child_process.h"
#include "coordinator/cli/bench/bench_plot.h"
#include "coordinator/cli/bench/pipeline_run.h"
#include "coordinator/cli/bench/radiance_runner.h"

namespace portico::cli {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

std::string textOf(const fs::path& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// "a;b;c" -> its non-blank parts; with ' ', the words (split at any white
// space: render_args.txt ends in a newline).
std::vector<std::string> partsOf(const std::string& text, char separator) {
  std::vector<std::string> parts;
  if (separator == ' ') {
    std::istringstream words(text);
    for (std::string word; words >> word;) parts.push_back(word);
    return parts;
  }
  size_t start = 0;
  while (start <= text.size()) {
    const size_t end = std::min(text.find(separator, start), text.size());
    const std::string part = text.substr(start, end - start);
    if (part.find_first_not_of(" \n") != std::string::npos) parts.push_back(part);
    start = end + 1;
  }
  return parts;
}

double timedChild(const std::vector<std::string>& argv, const fs::path& log, const std::string& what) {
  const auto started = Clock::now();
  ChildProcess child(argv, log.string());
  if (child.wait() != 0) throw std::runtime_error(fmt::format("{} failed:\n{}", what, textOf(log)));
  return std::chrono::duration<double>(Clock::now() - started).count();
}

// One CSV line's cells, empty ones kept, quoted ones (RFC 4180) unquoted.
std::vector<std::string> csvCells(const std::string& line) {
  std::vector<std::string> cells(1);
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (c == '"' && quoted && i + 1 < line.size() && line[i + 1] == '"') cells.back() += line[++i];
    else if (c == '"') quoted = !quoted;
    else if (c == ',' && !quoted) cells.emplace_back();
    else if (c != '\r') cells.back() += c;
  }
  return cells;
}

// The column `name` of a CSV whose first line not starting with '#' is its header.
std::vector<double> csvColumn(const fs::path& path, const std::string& name) {
  std::ifstream in(path);
  std::vector<double> values;
  int column = -1;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    const std::vector<std::string> cells = csvCells(line);
    if (column < 0) {
      const auto found = std::find(cells.begin(), cells.end(), name);
      if (found == cells.end()) throw std::runtime_error(fmt::format("{}: no column {}", path.string(), name));
      column = int(found - cells.begin());
      continue;
    }
    // A sensor outside every cell has an empty reading.
    values.push_back(column < int(cells.size()) && !cells[column].empty() ? std::stod(cells[column])
                                                                          : std::numeric_limits<double>::quiet_NaN());
  }
  return values;
}

struct Errors {
  double rms = 0, max = 0;   // relative, over the sensors with light in the reference
  double meanRatio = 0;      // mean over sensors / the reference's mean, minus 1
};

Errors errorsAgainst(const std::vector<double>& values, const std::vector<double>& reference) {
  if (values.size() != reference.size())
    throw std::runtime_error(fmt::format("{} readings for {} reference sensors", values.size(), reference.size()));
  Errors e;
  double squares = 0, sum = 0, referenceSum = 0;
  size_t counted = 0;
  for (size_t i = 0; i < values.size(); ++i) {
    if (!(reference[i] > 0) || !std::isfinite(values[i])) continue;
    const double relative = values[i] / reference[i] - 1;
    squares += relative * relative;
    e.max = std::max(e.max, std::abs(relative));
    sum += values[i];
    referenceSum += reference[i];
    ++counted;
  }
  e.rms = counted ? std::sqrt(squares / counted) : 0;
  e.meanRatio = referenceSum > 0 ? sum / referenceSum - 1 : 0;
  return e;
}

struct Rung {
  std::string program, settings;
  double seconds = 0;
  Errors own, other;   // against its own program's converged reference, and against the other's
};

// Seconds for an RMS error of `target`, between the first rung that reaches
// it and the one before (log-log); NaN when no rung does.
double secondsToReach(const std::vector<Rung>& rungs, double target) {
  for (size_t i = 0; i < rungs.size(); ++i) {
    if (rungs[i].own.rms > target) continue;
    if (i == 0 || rungs[i - 1].own.rms <= rungs[i].own.rms) return rungs[i].seconds;
    const double t = std::log(rungs[i - 1].own.rms / target) / std::log(rungs[i - 1].own.rms / rungs[i].own.rms);
    return std::exp(std::log(rungs[i - 1].seconds) + t * std::log(rungs[i].seconds / rungs[i - 1].seconds));
  }
  return std::numeric_limits<double>::quiet_NaN();
}

std::string percent(double v) { return fmt::format("{:.2f} %", 100 * v); }

void writeComparisonCsv(const std::string& path, const std::vector<Rung>& rungs) {
  std::ofstream out(path);
  out << "program,settings,seconds,rms_rel_err,max_rel_err,mean_err,rms_rel_err_vs_other_reference,"
         "mean_err_vs_other_reference\n";
  for (const Rung& r : rungs)
    out << fmt::format("{},\"{}\",{:.3f},{:.5f},{:.5f},{:.5f},{:.5f},{:.5f}\n", r.program, r.settings, r.seconds,
                       r.own.rms, r.own.max, r.own.meanRatio, r.other.rms, r.other.meanRatio);
  if (!out) throw std::runtime_error(fmt::format("{}: cannot write", path));
}

void plotComparison(const std::string& path, const std::string& scene, const std::vector<Rung>& rungs) {
  PlotPanel panel{fmt::format("{}: sensor error against time", scene), "seconds (start-up included)",
                  "relative RMS error over sensors", true, true, {}};
  PlotSeries radiance, portico;
  radiance.label = "Radiance", radiance.color = {214, 39, 40};
  portico.label = "portico", portico.color = {31, 119, 180};
  for (const Rung& r : rungs) {
    PlotSeries& s = r.program == "radiance" ? radiance : portico;
    s.x.push_back(r.seconds), s.y.push_back(r.own.rms);
  }
  panel.series = {radiance, portico};
  writePlotPng(path, {panel});
}

int runComparison(const BenchAnalyzeOptions& o) {
  const fs::path sceneDir(o.sceneDirectory), scene = sceneDir / "scene.json", sensors = sceneDir / "sensors.pts";
  for (const fs::path& needed : {scene, sensors})
    if (!fs::exists(needed)) throw std::invalid_argument(fmt::format("{}: no {}", o.sceneDirectory, needed.filename().string()));
  const std::optional<RadianceInstall> radiance = findRadiance();
  if (!radiance)
    throw std::runtime_error("no Radiance: deploy/install-deps.sh installs it (pyradiance) into the sources' .venv");
  const std::vector<std::string> radianceLadder = partsOf(o.radianceSettings, ';');
  const std::vector<std::string> porticoLadder = partsOf(o.porticoSettings, ';');
  const std::vector<std::string> daylight = partsOf(textOf(sceneDir / "render_args.txt"), ' ');

  const fs::path work = fs::temp_directory_path() / fmt::format("portico-bench-analyze-{}", getpid());
  fs::remove_all(work);
  fs::create_directories(work);
  const std::string portico = findProgram("portico"), store = (work / "store").string();
  timedChild({portico, "scene", "import", scene.string(), store}, work / "import.log", "importing " + scene.string());
  std::vector<std::string> exportCommand{portico, "scene", "export", store, "-o", (work / "scene.rad").string()};
  exportCommand.insert(exportCommand.end(), daylight.begin(), daylight.end());
  timedChild(exportCommand, work / "export.log", "scene export");
  std::vector<std::string> oconv{"oconv"};
  if (!daylight.empty()) oconv.push_back((work / "scene.sky.rad").string());
  oconv.push_back((work / "scene.rad").string());
  runRadiance(*radiance, oconv, "", (work / "scene.oct").string(), (work / "oconv.log").string());

  auto rtrace = [&](const std::string& settings, const std::string& tag) {
    std::vector<std::string> argv{"rtrace", "-h", "-I"};
    for (const std::string& word : partsOf(settings, ' ')) argv.push_back(word);
    argv.push_back((work / "scene.oct").string());
    const fs::path out = work / (tag + ".txt");
    const auto started = Clock::now();
    runRadiance(*radiance, argv, sensors.string(), out.string(), (work / (tag + ".log")).string());
    const double seconds = std::chrono::duration<double>(Clock::now() - started).count();
    std::vector<double> lux;
    for (const Vec3& e : readRtraceIrradiance(out.string())) lux.push_back(luxOf(e));
    return std::make_pair(seconds, lux);
  };
  auto analyze = [&](const std::string& settings, const std::string& tag) {
    const fs::path out = work / (tag + ".csv");
    std::vector<std::string> argv{portico, "analyze", store, "-o", out.string(), "--sensors", sensors.string(),
                                  "--workers", std::to_string(o.workers)};
    argv.insert(argv.end(), daylight.begin(), daylight.end());
    for (const std::string& word : partsOf(settings, ' ')) argv.push_back(word);
    const double seconds = timedChild(argv, work / (tag + ".log"), "portico analyze " + settings);
    return std::make_pair(seconds, csvColumn(out, "lux"));
  };

  std::cout << fmt::format("{}: {}; load {}\n", scene.string(), sensors.string(), loadAverage());
  std::vector<double> radianceReference;
  if (fs::exists(sceneDir / "radiance_reference.csv")) {
    radianceReference = csvColumn(sceneDir / "radiance_reference.csv", "lux");
    std::cout << fmt::format("Radiance reference: {} (stored)\n", (sceneDir / "radiance_reference.csv").string());
  } else {
    double seconds = 0;
    std::tie(seconds, radianceReference) = rtrace(o.radianceReference, "radiance-reference");
    std::cout << fmt::format("Radiance reference: rtrace -I {}: {:.1f} s\n", o.radianceReference, seconds);
  }
  const auto [porticoReferenceSeconds, porticoReference] = analyze(o.porticoReference, "portico-reference");
  std::cout << fmt::format("portico reference: analyze {}: {:.1f} s\n", o.porticoReference, porticoReferenceSeconds);
  const Errors between = errorsAgainst(porticoReference, radianceReference);
  std::cout << fmt::format("portico's reference against Radiance's: RMS {}, largest {}, mean over sensors {:+.2f} %\n",
                           percent(between.rms), percent(between.max), 100 * between.meanRatio);

  std::vector<Rung> rungs;
  std::cout << "program,settings,seconds,rms_rel_err,max_rel_err,rms_rel_err_vs_other_reference\n";
  auto record = [&](const std::string& program, const std::string& settings, double seconds,
                    const std::vector<double>& lux) {
    const bool isRadiance = program == "radiance";
    Rung r{program, settings, seconds, errorsAgainst(lux, isRadiance ? radianceReference : porticoReference),
           errorsAgainst(lux, isRadiance ? porticoReference : radianceReference)};
    std::cout << fmt::format("{},\"{}\",{:.2f},{:.4f},{:.4f},{:.4f}\n", program, settings, seconds, r.own.rms, r.own.max,
                             r.other.rms)
              << std::flush;
    rungs.push_back(r);
  };
  for (size_t i = 0; i < radianceLadder.size(); ++i) {
    const auto [seconds, lux] = rtrace(radianceLadder[i], fmt::format("radiance-{}", i));
    record("radiance", radianceLadder[i], seconds, lux);
  }
  for (size_t i = 0; i < porticoLadder.size(); ++i) {
    const auto [seconds, lux] = analyze(porticoLadder[i], fmt::format("portico-{}", i));
    record("portico", porticoLadder[i], seconds, lux);
  }

  std::vector<Rung> radianceRungs, porticoRungs;
  for (const Rung& r : rungs) (r.program == "radiance" ? radianceRungs : porticoRungs).push_back(r);
  std::cout << "\n| RMS error over sensors | Radiance rtrace -I | portico analyze |\n|---|---|---|\n";
  for (double target : {0.05, 0.02, 0.01}) {
    auto cell = [&](const std::vector<Rung>& ladder) {
      const double s = secondsToReach(ladder, target);
      return std::isfinite(s) ? fmt::format("{:.1f} s", s) : std::string("not reached");
    };
    std::cout << fmt::format("| {} | {} | {} |\n", percent(target), cell(radianceRungs), cell(porticoRungs));
  }
  if (!o.csv.empty()) writeComparisonCsv(o.csv, rungs);
  if (!o.plot.empty()) plotComparison(o.plot, sceneDir.filename().string(), rungs);
  fs::remove_all(work);
  return 0;
}

int runScale(const BenchAnalyzeOptions& o) {
  const std::string portico = findProgram("portico");
  const fs::path work = fs::temp_directory_path() / fmt::format("portico-bench-analyze-{}", getpid());
  fs::create_directories(work);
  const fs::path stores = o.storeDirectory.empty() ? work : fs::path(o.storeDirectory);
  fs::create_directories(stores);
  std::ofstream csv;
  if (!o.csv.empty()) {
    csv.open(o.csv);
    csv << "building,cells,rooms,sensors,workers,seconds,photon_seconds,sensor_seconds,photons,rays,bytes_read,"
           "cells_loaded,job_bytes,samples_per_sensor,peak_rss_worker_mib,peak_rss_coordinator_mib\n";
  }
  std::cout << "| building | rooms | sensors | wall (job's photon pass, sensors) | photons | cell bytes read (loads) | "
               "job's files | peak memory: worker, coordinator |\n|---|---|---|---|---|---|---|---|\n";
  for (const std::string& spec : partsOf(o.buildings, ',')) {
    const size_t colon = spec.find(':');
    const std::string preset = spec.substr(0, colon);
    const std::string floors = colon == std::string::npos ? "" : spec.substr(colon + 1);
    const fs::path store = stores / (floors.empty() ? preset : preset + floors);
    if (!fs::exists(store / "scene.db")) {
      std::vector<std::string> generate{portico, "scene", "generate", "--preset", preset};
      if (!floors.empty()) generate.insert(generate.end(), {"--floors", floors});
      generate.push_back(store.string());
      timedChild(generate, work / (preset + "-generate.log"), "generating " + spec);
    }
    const SceneStore scene = SceneStore::open(store.string());
    // The work-plane grid of `analyze --grid auto`, written first so that
    // its rooms and points can be counted ("N points in M rooms, ...").
    const fs::path pts = work / (preset + floors + ".pts"), gridLog = work / (preset + floors + "-grid.log");
    timedChild({portico, "scene", "grid", store.string(), "-o", pts.string()}, gridLog, "scene grid " + spec);
    std::smatch counted;
    const std::string gridSummary = textOf(gridLog);
    static const std::regex kCounts(R"((\d+) points in (\d+) rooms)");
    if (!std::regex_search(gridSummary, counted, kCounts))
      throw std::runtime_error("portico scene grid printed no count: " + gridSummary);
    const uint64_t sensors = std::stoull(counted[1]), rooms = std::stoull(counted[2]);
    const fs::path out = work / (preset + floors + ".csv");
    std::vector<std::string> argv{portico, "analyze", store.string(), "-o", out.string(), "--sensors", pts.string(),
                                  "--workers", std::to_string(o.workers), "--memory", o.memory};
    for (const std::string& word : partsOf(o.analyzeArguments, ' ')) argv.push_back(word);
    const double seconds = timedChild(argv, work / (preset + floors + "-analyze.log"), "portico analyze " + spec);
    // The job's own statistics, beside its results (job_report.cpp's keys).
    const nlohmann::json stats = nlohmann::json::parse(textOf(out.string() + ".json"));
    auto number = [&](const char* section, const char* key) { return stats.at(section).value(key, 0.0); };
    const double mib = 1024.0 * 1024.0;
    const double workerPeak = number("memory", "workers_peak_rss_bytes") / mib;
    const double coordinatorPeak = number("memory", "coordinator_peak_rss_bytes") / mib;
    std::cout << fmt::format(
                     "| {} | {} | {} | {:.1f} s (photons {:.1f} s, sensors {:.1f} s) | {:.0f} | {:.2f} GB ({} loads) | "
                     "{:.2f} GB | {:.0f} MiB, {:.0f} MiB |\n",
                     spec, rooms, sensors, seconds, number("time_ms", "photons") / 1e3, number("time_ms", "render") / 1e3,
                     number("photons", "emitted"), number("cells", "bytes_read") / 1e9, number("cells", "loaded"),
                     number("disk", "job_bytes") / 1e9, workerPeak, coordinatorPeak)
              << std::flush;
    if (csv.is_open())
      csv << fmt::format("{},{},{},{},{},{:.2f},{:.2f},{:.2f},{:.0f},{:.0f},{:.0f},{:.0f},{:.0f},{:.0f},{:.1f},{:.1f}\n",
                         spec, scene.cells().size(), rooms, sensors, o.workers, seconds, number("time_ms", "photons") / 1e3,
                         number("time_ms", "render") / 1e3, number("photons", "emitted"), number("rays", "traced"),
                         number("cells", "bytes_read"), number("cells", "loaded"), number("disk", "job_bytes"),
                         number("analysis", "samples_per_sensor"), workerPeak, coordinatorPeak);
  }
  fs::remove_all(work);
  return 0;
}

}  // namespace

int runBenchAnalyze(const BenchAnalyzeOptions& options) {
  if (options.buildings.empty() == options.sceneDirectory.empty())
    throw std::invalid_argument("bench analyze: give a SCENE_DIR (Radiance beside portico) or --buildings (the scale run)");
  return options.buildings.empty() ? runComparison(options) : runScale(options);
}

}  // namespace portico::cli
