#include "coordinator/cli/bench/bench_analyze.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
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

// "a;b;c" -> its non-blank parts; "x y" -> its words.
std::vector<std::string> partsOf(const std::string& text, char separator) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t end = std::min(text.find(separator, start), text.size());
    const std::string part = text.substr(start, end - start);
    if (part.find_first_not_of(' ') != std::string::npos) parts.push_back(part);
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

// The column `name` of a CSV whose first line not starting with '#' is its header.
std::vector<double> csvColumn(const fs::path& path, const std::string& name) {
  std::ifstream in(path);
  std::vector<double> values;
  int column = -1;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    const std::vector<std::string> cells = partsOf(line, ',');
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
  PlotPanel panel{fmt::format("{}: sensor error against time", scene), "seconds (whole run, start-up included)",
                  "relative RMS error over sensors (own converged reference)", true, true, {}};
  PlotSeries radiance, portico;
  radiance.label = "Radiance rtrace -I", radiance.color = {214, 39, 40};
  portico.label = "portico analyze", portico.color = {31, 119, 180};
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

// Work-plane sensors in every room cell (named *room*), from its box: 0.8 m
// above its floor, every 0.5 m, 0.5 m in from its walls (one at the centre
// of a room narrower than that), facing up. No furniture test: a sensor may
// stand in a cupboard (--grid auto skips those).
uint64_t writeRoomSensors(const SceneStore& store, const fs::path& path, uint64_t& rooms) {
  std::ofstream out(path);
  uint64_t count = 0;
  for (const CellInfo& cell : store.cells()) {
    if (cell.name.find("room") == std::string::npos) continue;
    ++rooms;
    auto positions = [](float lo, float hi) {
      std::vector<float> p;
      for (float v = lo + 0.5f; v <= hi - 0.5f + 1e-4f; v += 0.5f) p.push_back(v);
      if (p.empty()) p.push_back(0.5f * (lo + hi));
      return p;
    };
    for (float x : positions(cell.bounds.lo.x, cell.bounds.hi.x))
      for (float z : positions(cell.bounds.lo.z, cell.bounds.hi.z)) {
        out << fmt::format("{} {} {} 0 1 0\n", x, cell.bounds.lo.y + 0.8f, z);
        ++count;
      }
  }
  return count;
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
    csv << "building,cells,rooms,sensors,workers,seconds,cpu_seconds,photons,bytes_read,cells_loaded,"
           "peak_rss_worker_mib,peak_rss_coordinator_mib\n";
  }
  std::cout << "| building | rooms | sensors | wall | CPU | photons | bytes read (cells loaded) | peak memory: worker, "
               "coordinator |\n|---|---|---|---|---|---|---|---|\n";
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
    uint64_t rooms = 0;
    const fs::path pts = work / (preset + floors + ".pts");
    const uint64_t sensors = writeRoomSensors(scene, pts, rooms);
    const fs::path out = work / (preset + floors + ".csv");
    std::vector<std::string> argv{portico, "analyze", store.string(), "-o", out.string(), "--sensors", pts.string(),
                                  "--workers", std::to_string(o.workers), "--memory", o.memory};
    for (const std::string& word : partsOf(o.analyzeArguments, ' ')) argv.push_back(word);
    const double cpuBefore = cpuSeconds(RUSAGE_CHILDREN);
    const double seconds = timedChild(argv, work / (preset + floors + "-analyze.log"), "portico analyze " + spec);
    const double cpu = cpuSeconds(RUSAGE_CHILDREN) - cpuBefore;
    PipelineRunStats stats;
    nlohmann::json statistics;
    int64_t workerPeak = 0, coordinatorPeak = 0;
    if (fs::exists(out.string() + ".json")) {
      statistics = nlohmann::json::parse(textOf(out.string() + ".json"));
      stats = parsePipelineStatistics(statistics);
      for (const auto& [key, value] : statistics.value("counters", nlohmann::json::object()).items()) {
        if (key.rfind("memory.peak_rss.worker.", 0) == 0) workerPeak = std::max<int64_t>(workerPeak, value.get<int64_t>());
        if (key == "memory.peak_rss.coordinator") coordinatorPeak = value.get<int64_t>();
      }
    }
    const double mib = 1024.0 * 1024.0;
    std::cout << fmt::format("| {} | {} | {} | {:.1f} s | {:.1f} s | {} | {:.2f} GB ({}) | {:.0f} MiB, {:.0f} MiB |\n", spec,
                             rooms, sensors, seconds, cpu, stats.emitted, stats.bytesRead / 1e9, stats.cellsLoaded,
                             workerPeak / mib, coordinatorPeak / mib)
              << std::flush;
    if (csv.is_open())
      csv << fmt::format("{},{},{},{},{},{:.2f},{:.2f},{},{},{},{:.1f},{:.1f}\n", spec, scene.cells().size(), rooms,
                         sensors, o.workers, seconds, cpu, stats.emitted, stats.bytesRead, stats.cellsLoaded,
                         workerPeak / mib, coordinatorPeak / mib);
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
