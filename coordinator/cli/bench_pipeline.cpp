// `portico bench pipeline`: the same photon pass over a generated building,
// three ways (or the modes asked for):
//
//   embree-incore-2t  every cell's triangles in one Embree BVH, two threads
//                     tracing the photons through the whole building
//                     (incore_photon_tracer.h): what a user would write
//                     instead of portico. seconds = load + BVH build + trace.
//   portico-1w/-2w    the real pipeline: `portico render` as a child process
//                     with 1 or 2 workers (one tracing thread each), the
//                     photon pass plus a token render (8x8 pixels, 1 spp, no
//                     gathering). seconds = the coordinator's photon phase
//                     (time_ms.photons of the statistics JSON: from the
//                     job's submission to its last photon Result committed,
//                     cells loaded and accelerators built on the way).
//
// Each mode runs `--runs` times, interleaved (so that a slow minute of a
// shared machine hurts every mode alike); the median is reported. Deposits
// and absorbed/escaped photons are printed for every mode so that one can
// see that they do the same work.
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
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/scene/building_generator.h"
#include "common/scene/building_presets.h"
#include "common/scene/scene_store.h"
#include "common/util/child_process.h"
#include "coordinator/cli/commands.h"
#include "coordinator/cli/incore_photon_tracer.h"
#include "coordinator/cli/png_canvas.h"

namespace portico::cli {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// CPU seconds (user + system) used so far by this process (RUSAGE_SELF: all
// its threads) or by its waited-for descendants (RUSAGE_CHILDREN: `portico
// render` and the coordinator and workers it waited for).
double cpuSeconds(int who) {
  rusage usage{};
  getrusage(who, &usage);
  const auto seconds = [](const timeval& t) { return double(t.tv_sec) + double(t.tv_usec) * 1e-6; };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

// The 1-minute load average ("?" where /proc/loadavg cannot be read): a
// shared machine's other work shows up here, and in the timings.
std::string loadAverage() {
  std::ifstream in("/proc/loadavg");
  std::string first;
  return in >> first ? first : "?";
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n == 0 ? 0.0 : (n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]));
}

struct Mode {
  std::string name;
  uint32_t workers = 0;  // 0: the in-core Embree tracer
};

// "embree-incore-2t,portico-1w,portico-2w" -> modes; portico-Nw for any N.
std::vector<Mode> parseModes(const std::string& text) {
  std::vector<Mode> modes;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (item.empty()) continue;
    Mode mode{item, 0};
    if (item == "embree-incore-2t") {
      mode.workers = 0;
    } else if (item.rfind("portico-", 0) == 0 && item.size() > 9 && item.back() == 'w') {
      const std::string digits = item.substr(8, item.size() - 9);
      if (digits.find_first_not_of("0123456789") != std::string::npos || digits.size() > 3 || std::stoul(digits) == 0)
        throw std::invalid_argument("--modes: '" + item + "' is not portico-Nw with N >= 1");
      mode.workers = uint32_t(std::stoul(digits));
    } else {
      throw std::invalid_argument("--modes: unknown mode '" + item + "' (embree-incore-2t, portico-1w, portico-2w, ...)");
    }
    modes.push_back(mode);
  }
  if (modes.empty()) throw std::invalid_argument("--modes: nothing to run");
  return modes;
}

// One run of one mode.
struct Sample {
  double seconds = 0;       // the photon pass as defined above
  double loadSeconds = 0;   // in-core: mapping the cell files
  double buildSeconds = 0;  // in-core: BVH; portico: accelerator builds summed over workers
  double traceSeconds = 0;  // in-core only
  double wallSeconds = 0;   // the whole run (portico: the child process, render phase and start-up included)
  double cpuSeconds = 0;    // CPU time of that whole run, every thread and process
  int64_t emitted = 0, deposits = 0, absorbed = 0, escaped = 0, rays = 0, crossings = 0, portalCopies = 0;
  int64_t cellsLoaded = 0, cacheHits = 0, bytesRead = 0, leases = 0;
};

struct ModeResult {
  Mode mode;
  std::vector<Sample> samples;
  // The sample whose seconds is the median (the lower middle one for an even count).
  const Sample& typical() const {
    std::vector<size_t> order(samples.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return samples[a].seconds < samples[b].seconds; });
    return samples[order[(order.size() - 1) / 2]];
  }
  double seconds() const {
    std::vector<double> s;
    for (const Sample& sample : samples) s.push_back(sample.seconds);
    return median(s);
  }
};

int64_t jsonInt(const nlohmann::json& j, const char* section, const char* key) {
  if (!j.contains(section) || !j[section].contains(key)) return 0;
  return j[section][key].get<int64_t>();
}

Sample runInCore(const SceneStore& scene, const BenchPipelineOptions& options) {
  InCorePhotonOptions incore;
  incore.photons = options.photons;
  incore.seed = options.seed;
  incore.threads = 2;
  const auto start = Clock::now();
  const double cpuStart = cpuSeconds(RUSAGE_SELF);
  const InCorePhotonResult r = runInCorePhotonTracer(scene, incore);
  Sample sample;
  sample.wallSeconds = secondsSince(start);
  sample.cpuSeconds = cpuSeconds(RUSAGE_SELF) - cpuStart;
  sample.loadSeconds = r.loadSeconds;
  sample.buildSeconds = r.buildSeconds;
  sample.traceSeconds = r.traceSeconds;
  sample.seconds = r.loadSeconds + r.buildSeconds + r.traceSeconds;
  sample.emitted = r.emitted;
  sample.deposits = r.deposits;
  sample.absorbed = r.absorbed;
  sample.escaped = r.escaped;
  sample.rays = r.rays;
  sample.cellsLoaded = r.cells;
  sample.bytesRead = int64_t(r.bytesMapped);
  std::cout << fmt::format(
      "  embree-incore-2t: {} cells, {} triangles, BVH {:.0f} MiB; load {:.2f} s, build {:.2f} s (device {:.3f} s), "
      "trace {:.2f} s; {} rays; CPU {:.2f} s\n",
      r.cells, r.triangles, double(r.bvhBytes) / (1 << 20), r.loadSeconds, r.buildSeconds, r.deviceSeconds,
      r.traceSeconds, r.rays, sample.cpuSeconds);
  return sample;
}

Sample runPortico(const std::string& store, uint32_t workers, const BenchPipelineOptions& options,
                  const std::filesystem::path& work, size_t runIndex) {
  const std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
  const std::filesystem::path output = work / fmt::format("portico-{}w-{}.exr", workers, runIndex);
  const std::filesystem::path log = work / fmt::format("portico-{}w-{}.log", workers, runIndex);
  // The photon pass, and the smallest render a job can have.
  const std::vector<std::string> argv{self, "render", store, "-o", output.string(),
                                      "--workers", std::to_string(workers),
                                      "--photons", std::to_string(options.photons),
                                      "--seed", std::to_string(options.seed),
                                      "--spp", "1", "--gather", "0", "--width", "8", "--height", "8",
                                      "--accel", options.accel, "--memory", options.memory, "--log-level", "warn"};
  const auto start = Clock::now();
  const double cpuStart = cpuSeconds(RUSAGE_CHILDREN);
  ChildProcess child(argv, log.string());
  const int status = child.wait();
  Sample sample;
  sample.wallSeconds = secondsSince(start);
  sample.cpuSeconds = cpuSeconds(RUSAGE_CHILDREN) - cpuStart;
  if (status != 0) {
    std::ifstream in(log);
    std::stringstream text;
    text << in.rdbuf();
    throw std::runtime_error(fmt::format("portico render with {} worker(s) failed (status {}); its output ({}):\n{}",
                                         workers, status, log.string(), text.str()));
  }
  const std::string statisticsPath = output.string() + ".json";
  std::ifstream in(statisticsPath);
  if (!in) throw std::runtime_error("portico render wrote no statistics at " + statisticsPath);
  const nlohmann::json stats = nlohmann::json::parse(in);
  sample.seconds = double(jsonInt(stats, "time_ms", "photons")) / 1e3;
  sample.buildSeconds = double(jsonInt(stats, "time_ms", "accelerator_build")) / 1e3;
  sample.emitted = jsonInt(stats, "photons", "emitted");
  sample.deposits = jsonInt(stats, "photons", "deposits");
  sample.absorbed = jsonInt(stats, "photons", "absorbed");
  sample.escaped = jsonInt(stats, "photons", "escaped");
  sample.crossings = jsonInt(stats, "photons", "crossings");
  sample.portalCopies = jsonInt(stats, "photons", "portal_copies");
  sample.cellsLoaded = jsonInt(stats, "cells", "loaded");
  sample.cacheHits = jsonInt(stats, "cells", "cache_hits");
  sample.bytesRead = jsonInt(stats, "cells", "bytes_read");
  sample.leases = stats.contains("leases") ? stats["leases"].get<int64_t>() : 0;
  // Rays traced counts camera rays too, but the token render has 64 of them
  // and their shadow rays: near enough the photon segments.
  sample.rays = jsonInt(stats, "rays", "traced");
  std::cout << fmt::format(
      "  portico-{}w: photon phase {:.2f} s (process {:.2f} s, CPU {:.2f} s); {} cells loaded, {} cache hits, "
      "{:.0f} MiB read, accelerators {:.2f} s (all workers); {} leases, {} portal crossings, {} portal copies\n",
      workers, sample.seconds, sample.wallSeconds, sample.cpuSeconds, sample.cellsLoaded, sample.cacheHits,
      double(sample.bytesRead) / (1 << 20), sample.buildSeconds, sample.leases, sample.crossings,
      sample.portalCopies);
  std::error_code ignored;
  std::filesystem::remove(output, ignored);
  std::filesystem::remove(statisticsPath, ignored);
  std::filesystem::remove(log, ignored);
  return sample;
}

// Bars of photons/s per mode, each labelled with its value and its ratio to
// the in-core Embree tracer; drawn on the canvas of `portico bench --plot`.
void writeBarPlot(const std::string& path, const std::string& title, const std::vector<ModeResult>& results,
                  uint64_t photons, double embreeRate) {
  constexpr int kWidth = 760, kHeight = 480;
  constexpr int kLeft = 110, kRight = 30, kTop = 60, kBottom = 70;
  Canvas canvas(kWidth, kHeight);
  canvas.text((kWidth - textWidth(title)) / 2, 16, title, kBlack);
  std::vector<double> rates;
  for (const ModeResult& r : results) rates.push_back(r.seconds() > 0 ? double(photons) / r.seconds() : 0.0);
  const double maxRate = std::max(1.0, *std::max_element(rates.begin(), rates.end()));
  // The largest 1-2-5 step that gives at least 4 ticks.
  double step = 0;
  for (double decade = std::pow(10.0, std::floor(std::log10(maxRate))); step == 0; decade /= 10)
    for (double mantissa : {5.0, 2.0, 1.0})
      if (step == 0 && maxRate / (mantissa * decade) >= 4) step = mantissa * decade;
  const double top = std::ceil(maxRate * 1.15 / step) * step;
  const int plotWidth = kWidth - kLeft - kRight, plotHeight = kHeight - kTop - kBottom;
  const auto yOf = [&](double value) { return kTop + plotHeight - int(std::lround(value / top * plotHeight)); };
  for (double tick = 0; tick <= top * 1.0001; tick += step) {
    const int y = yOf(tick);
    canvas.line(kLeft, y, kLeft + plotWidth, y, kLightGrey, 1, false);
    const std::string label = tick >= 1e6 ? fmt::format("{:g}M", tick / 1e6)
                              : tick >= 1e3 ? fmt::format("{:g}k", tick / 1e3)
                                            : fmt::format("{:g}", tick);
    canvas.text(kLeft - 8 - textWidth(label), y - kTextHeight / 2, label, kBlack);
  }
  canvas.line(kLeft, kTop, kLeft, kTop + plotHeight, kBlack, 1, false);
  canvas.line(kLeft, kTop + plotHeight, kLeft + plotWidth, kTop + plotHeight, kBlack, 1, false);
  canvas.text(12, kTop + plotHeight / 2 + textWidth("photons/s") / 2, "photons/s", kBlack, true);
  static constexpr Color kColors[] = {{90, 90, 90}, {31, 119, 180}, {44, 160, 44}, {255, 127, 14}, {148, 103, 189}};
  const int slot = plotWidth / int(results.size());
  const int barWidth = std::min(140, slot * 3 / 5);
  for (size_t i = 0; i < results.size(); ++i) {
    const int x0 = kLeft + int(i) * slot + (slot - barWidth) / 2;
    const int y = yOf(rates[i]);
    canvas.fill(x0, y, x0 + barWidth, kTop + plotHeight - 1,
                results[i].mode.workers == 0 ? kColors[0] : kColors[1 + (results[i].mode.workers - 1) % 4]);
    const std::string value = rates[i] >= 1e6 ? fmt::format("{:.2f}M", rates[i] / 1e6)
                                              : fmt::format("{:.0f}k", rates[i] / 1e3);
    const std::string ratio = embreeRate > 0 ? fmt::format("x{:.2f}", rates[i] / embreeRate) : "";
    canvas.text(x0 + (barWidth - textWidth(value)) / 2, y - 2 * kTextHeight - 10, value, kBlack);
    canvas.text(x0 + (barWidth - textWidth(ratio)) / 2, y - kTextHeight - 4, ratio, kGrey);
    const std::string& name = results[i].mode.name;
    canvas.text(x0 + (barWidth - textWidth(name)) / 2, kTop + plotHeight + 12, name, kBlack);
    const std::string seconds = fmt::format("{:.1f} s", results[i].seconds());
    canvas.text(x0 + (barWidth - textWidth(seconds)) / 2, kTop + plotHeight + 12 + kTextHeight + 8, seconds, kGrey);
  }
  writePng(path, canvas, "pipeline benchmark plot");
}

}  // namespace

int runBenchPipeline(const BenchPipelineOptions& options) {
  if (options.photons == 0) throw std::invalid_argument("--photons must be at least 1");
  const std::vector<Mode> modes = parseModes(options.modes);
  const uint32_t runs = std::max<uint32_t>(1, options.runs);
  const std::optional<BuildingPreset> preset = findBuildingPreset(options.preset, options.floors);
  if (!preset)
    throw std::invalid_argument(fmt::format("unknown preset '{}' (known: {})", options.preset,
                                            fmt::join(buildingPresetNames(), ", ")));

  char pattern[] = "/tmp/portico-bench-pipeline-XXXXXX";
  if (!mkdtemp(pattern)) throw std::runtime_error("cannot create a temporary directory under /tmp");
  const std::filesystem::path work(pattern);
  struct RemoveOnExit {
    std::filesystem::path path;
    ~RemoveOnExit() {
      std::error_code ignored;
      std::filesystem::remove_all(path, ignored);
    }
  } removeWork{work};

  // The store: --store reused if it holds one, else generated there (and
  // kept), else generated into the temporary directory.
  std::string store = options.store.empty() ? (work / "store").string()
                                            : std::filesystem::absolute(options.store).string();
  const bool reuse = !options.store.empty() && std::filesystem::exists(std::filesystem::path(store) / "scene.db");
  if (reuse) {
    std::cout << fmt::format("portico bench pipeline: reusing the scene store {}\n", store);
  } else {
    std::cout << fmt::format("portico bench pipeline: generating {} into {} ...\n", options.preset, store);
    std::cout.flush();
    const GeneratedBuildingStats generated = generateBuilding(*preset, options.sceneSeed, store);
    std::cout << fmt::format("  {} triangles, {} cells, {} portals, {} lights in {:.1f} s\n", generated.triangles,
                             generated.cells, generated.portals, generated.lights, generated.seconds);
  }
  const SceneStore scene = SceneStore::open(store);
  uint64_t storeBytes = 0;
  for (const CellInfo& cell : scene.cells()) storeBytes += cell.byteCount;
  std::cout << fmt::format(
      "scene: {} cells, {} triangles, {} lights, {:.0f} MiB of cell files; {} photons, seed {}, portico accelerator "
      "'{}', worker memory {}; {} run(s) per mode, interleaved, median reported\n",
      scene.cells().size(), scene.totalTriangles(), scene.lights().size(), double(storeBytes) / (1 << 20),
      options.photons, options.seed, options.accel, options.memory, runs);
  std::cout.flush();

  std::vector<ModeResult> results;
  for (const Mode& mode : modes) results.push_back({mode, {}});
  for (uint32_t run = 0; run < runs; ++run) {
    for (ModeResult& result : results) {
      std::cout << fmt::format("run {}/{}: {} (load average {})\n", run + 1, runs, result.mode.name, loadAverage());
      std::cout.flush();
      result.samples.push_back(result.mode.workers == 0
                                   ? runInCore(scene, options)
                                   : runPortico(store, result.mode.workers, options, work, run));
      std::cout.flush();
    }
  }

  // The table.
  double embreeRate = 0;
  for (const ModeResult& r : results)
    if (r.mode.workers == 0 && r.seconds() > 0) embreeRate = double(options.photons) / r.seconds();
  const auto rateOf = [&](const ModeResult& r) { return r.seconds() > 0 ? double(options.photons) / r.seconds() : 0.0; };
  const auto ratioText = [&](double rate) { return embreeRate > 0 ? fmt::format("{:.2f}", rate / embreeRate) : ""; };
  std::cout << fmt::format("\n{:<18} {:>9} {:>9} {:>12} {:>9} {:>8} {:>8} {:>8} {:>10} {:>10} {:>10}\n", "mode",
                           "photons", "seconds", "photons/s", "x embree", "build s", "trace s", "CPU s", "deposits",
                           "absorbed", "escaped");
  std::string csv =
      "mode,photons,seconds,photons_per_s,ratio_to_embree,load_s,build_s,trace_s,wall_s,cpu_s,emitted,deposits,absorbed,"
      "escaped,rays,photon_crossings,portal_copies,cells_loaded,cache_hits,bytes_read,leases,runs,seconds_all\n";
  for (const ModeResult& r : results) {
    const Sample& s = r.typical();
    const double rate = rateOf(r);
    std::cout << fmt::format("{:<18} {:>9} {:>9.2f} {:>12.0f} {:>9} {:>8.2f} {:>8} {:>8.2f} {:>10} {:>10} {:>10}\n",
                             r.mode.name, options.photons, r.seconds(), rate, ratioText(rate), s.buildSeconds,
                             r.mode.workers == 0 ? fmt::format("{:.2f}", s.traceSeconds) : "", s.cpuSeconds,
                             s.deposits, s.absorbed, s.escaped);
    std::vector<std::string> all;
    for (const Sample& sample : r.samples) all.push_back(fmt::format("{:.3f}", sample.seconds));
    csv += fmt::format("{},{},{:.3f},{:.1f},{},{:.3f},{:.3f},{},{:.3f},{:.3f},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
                       r.mode.name, options.photons, r.seconds(), rate, ratioText(rate), s.loadSeconds,
                       s.buildSeconds, r.mode.workers == 0 ? fmt::format("{:.3f}", s.traceSeconds) : "",
                       s.wallSeconds, s.cpuSeconds, s.emitted, s.deposits, s.absorbed, s.escaped, s.rays, s.crossings,
                       s.portalCopies, s.cellsLoaded, s.cacheHits, s.bytesRead, s.leases, r.samples.size(),
                       fmt::join(all, " "));
  }
  std::cout << "build s: in-core, Embree's BVH (2 threads) after loading the cells; portico, its workers' "
               "accelerator builds added up (inside seconds). CPU s: the whole run's CPU time (portico: every "
               "process, start-up and token render included)\n";

  // Same work? Deposits of portico with any number of workers are the same
  // bits; the in-core tracer's differ only where a photon's path meets a
  // portal or Embree's triangle test disagrees with portico's in the last bit.
  const ModeResult* embree = nullptr;
  std::vector<const ModeResult*> porticos;
  for (const ModeResult& r : results) {
    if (r.mode.workers == 0)
      embree = &r;
    else
      porticos.push_back(&r);
  }
  int status = 0;
  for (const ModeResult* p : porticos) {
    const Sample& s = p->typical();
    if (s.emitted != int64_t(options.photons)) {
      std::cerr << fmt::format("portico: {} emitted {} photons, not {}\n", p->mode.name, s.emitted, options.photons);
      status = 3;
    }
    if (p != porticos.front() && s.deposits != porticos.front()->typical().deposits) {
      std::cerr << fmt::format("portico: {} deposited {} photons but {} deposited {}: not the same bits\n",
                               p->mode.name, s.deposits, porticos.front()->mode.name,
                               porticos.front()->typical().deposits);
      status = 3;
    }
  }
  if (embree && !porticos.empty()) {
    const Sample& e = embree->typical();
    const Sample& p = porticos.front()->typical();
    std::cout << fmt::format(
        "same work: deposits in-core {} vs portico {} ({:+.2f} %); absorbed {} vs {}; escaped {} vs {}\n", e.deposits,
        p.deposits, p.deposits ? 100.0 * double(e.deposits - p.deposits) / double(p.deposits) : 0.0, e.absorbed,
        p.absorbed, e.escaped, p.escaped);
  }
  for (const ModeResult* p : porticos)
    if (p->mode.workers > 1)
      for (const ModeResult* q : porticos)
        if (q->mode.workers == 1)
          std::cout << fmt::format("{} / {}: {:.2f}x\n", p->mode.name, q->mode.name, q->seconds() / p->seconds());

  if (!options.csv.empty()) {
    std::ofstream out(options.csv);
    out << csv;
    if (!out) throw std::runtime_error("cannot write " + options.csv + " (check the directory exists)");
    std::cout << "wrote " << options.csv << "\n";
  }
  if (!options.plot.empty()) {
    const std::string title =
        fmt::format("{}: {} photons, {} triangles", options.preset, options.photons, scene.totalTriangles());
    writeBarPlot(options.plot, title, results, options.photons, embreeRate);
    std::cout << "wrote " << options.plot << "\n";
  }
  return status;
}

}  // namespace portico::cli
