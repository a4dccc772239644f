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
#include "coordinator/cli/bench/bench_pipeline.h"

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

#include "common/scene/generator/building_generator.h"
#include "common/scene/generator/building_presets.h"
#include "common/scene/store/scene_store.h"
#include "common/util/temporary_directory.h"
#include "coordinator/cli/bench/incore_photon_tracer.h"
#include "coordinator/cli/bench/accel_measure.h"
#include "coordinator/cli/bench/bench_plot.h"
#include "coordinator/cli/bench/pipeline_run.h"

namespace portico::cli {

namespace {

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
  PipelineRunSpec spec;
  spec.store = store;
  spec.workers = workers;
  spec.photons = options.photons;
  spec.seed = options.seed;
  spec.accel = options.accel;
  spec.memory = options.memory;
  const PipelineRunStats stats = runPipeline(spec, work, fmt::format("portico-{}w-{}", workers, runIndex));
  Sample sample;
  sample.seconds = stats.photonSeconds;
  sample.buildSeconds = stats.buildSeconds;
  sample.wallSeconds = stats.wallSeconds;
  sample.cpuSeconds = stats.cpuSeconds;
  sample.emitted = stats.emitted;
  sample.deposits = stats.deposits;
  sample.absorbed = stats.absorbed;
  sample.escaped = stats.escaped;
  sample.crossings = stats.crossings;
  sample.portalCopies = stats.portalCopies;
  sample.cellsLoaded = stats.cellsLoaded;
  sample.cacheHits = stats.cacheHits;
  sample.bytesRead = stats.bytesRead;
  sample.leases = stats.leases;
  // Rays traced counts camera rays too, but the token render has 64 of them
  // and their shadow rays: near enough the photon segments.
  sample.rays = stats.raysTraced;
  std::cout << fmt::format(
      "  portico-{}w: photon phase {:.2f} s (process {:.2f} s, CPU {:.2f} s); {} cells loaded, {} cache hits, "
      "{:.0f} MiB read, accelerators {:.2f} s (all workers); {} leases, {} portal crossings, {} portal copies\n",
      workers, sample.seconds, sample.wallSeconds, sample.cpuSeconds, sample.cellsLoaded, sample.cacheHits,
      double(sample.bytesRead) / (1 << 20), sample.buildSeconds, sample.leases, sample.crossings,
      sample.portalCopies);
  return sample;
}

// Bars of photons/s per mode, each labelled with its value and its ratio to
// the in-core Embree tracer (bench_plot.h).
void writeBarPlot(const std::string& path, const std::string& title, const std::vector<ModeResult>& results,
                  uint64_t photons, double embreeRate) {
  static constexpr std::array<uint8_t, 3> kColors[] = {
      {90, 90, 90}, {31, 119, 180}, {44, 160, 44}, {255, 127, 14}, {148, 103, 189}};
  BarPanel panel;
  panel.title = title;
  panel.yLabel = "photons/s";
  for (const ModeResult& r : results) {
    const double rate = r.seconds() > 0 ? double(photons) / r.seconds() : 0.0;
    Bar bar;
    bar.value = rate;
    bar.color = r.mode.workers == 0 ? kColors[0] : kColors[1 + (r.mode.workers - 1) % 4];
    bar.above = rate >= 1e6 ? fmt::format("{:.2f}M", rate / 1e6) : fmt::format("{:.0f}k", rate / 1e3);
    bar.aboveNote = embreeRate > 0 ? fmt::format("x{:.2f}", rate / embreeRate) : "";
    panel.groups.push_back({r.mode.name, fmt::format("{:.1f} s", r.seconds()), {bar}});
  }
  writeBarPlotPng(path, {panel}, 760, 480);
}

// The store: --store reused if it holds one, else generated there (and
// kept), else generated into the temporary directory `work`.
std::string prepareStore(const BenchPipelineOptions& options, const BuildingPreset& preset,
                         const std::filesystem::path& work) {
  std::string store = options.store.empty() ? (work / "store").string()
                                            : std::filesystem::absolute(options.store).string();
  const bool reuse = !options.store.empty() && std::filesystem::exists(std::filesystem::path(store) / "scene.db");
  if (reuse) {
    std::cout << fmt::format("portico bench pipeline: reusing the scene store {}\n", store);
  } else {
    std::cout << fmt::format("portico bench pipeline: generating {} into {} ...\n", options.preset, store);
    std::cout.flush();
    const GeneratedBuildingStats generated = generateBuilding(preset, options.sceneSeed, store);
    std::cout << fmt::format("  {} triangles, {} cells, {} portals, {} lights in {:.1f} s\n", generated.triangles,
                             generated.cells, generated.portals, generated.lights, generated.seconds);
  }
  return store;
}

// --photons, or by default the paper's workload for the building: at 1 M
// photons the octagon's photon phase is ~1.5 s with one worker, a third of
// it loading and building its 233 cells, which the paper's 7.75 M amortise.
// At most 10 M: the in-core tracer keeps every deposit in memory (~130
// bytes per photon), and Soda Hall's 135 M would take 17 GiB of it.
uint64_t photonsOfPass(uint64_t requested, const SceneStore& scene, const std::string& store) {
  constexpr uint64_t kMostDefaultPhotons = 10000000;
  uint64_t photons = requested;
  if (photons == 0) {
    const uint64_t paperPhotons = kPaperPhotonsPerLight * scene.lights().size();
    photons = std::min(paperPhotons, kMostDefaultPhotons);
    if (paperPhotons > kMostDefaultPhotons)
      std::cout << fmt::format("photons: {} (the paper's 50 000 per light would be {}; --photons sets any count)\n",
                               photons, paperPhotons);
  }
  if (photons == 0) throw std::invalid_argument(fmt::format("the scene store {} has no lights", store));
  return photons;
}

// Every mode `runs` times, interleaved: a slow minute of a shared machine
// hurts every mode alike.
std::vector<ModeResult> runModes(const std::vector<Mode>& modes, uint32_t runs, const SceneStore& scene,
                                 const std::string& store, const BenchPipelineOptions& options,
                                 const std::filesystem::path& work) {
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
  return results;
}

// The table on stdout; returns the CSV's text. embreeRate: the in-core
// tracer's photons/s (0 when it did not run).
std::string printResults(const std::vector<ModeResult>& results, uint64_t photons, double embreeRate) {
  const auto rateOf = [&](const ModeResult& r) { return r.seconds() > 0 ? double(photons) / r.seconds() : 0.0; };
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
                             r.mode.name, photons, r.seconds(), rate, ratioText(rate), s.buildSeconds,
                             r.mode.workers == 0 ? fmt::format("{:.2f}", s.traceSeconds) : "", s.cpuSeconds,
                             s.deposits, s.absorbed, s.escaped);
    std::vector<std::string> all;
    for (const Sample& sample : r.samples) all.push_back(fmt::format("{:.3f}", sample.seconds));
    csv += fmt::format("{},{},{:.3f},{:.1f},{},{:.3f},{:.3f},{},{:.3f},{:.3f},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
                       r.mode.name, photons, r.seconds(), rate, ratioText(rate), s.loadSeconds,
                       s.buildSeconds, r.mode.workers == 0 ? fmt::format("{:.3f}", s.traceSeconds) : "",
                       s.wallSeconds, s.cpuSeconds, s.emitted, s.deposits, s.absorbed, s.escaped, s.rays, s.crossings,
                       s.portalCopies, s.cellsLoaded, s.cacheHits, s.bytesRead, s.leases, r.samples.size(),
                       fmt::join(all, " "));
  }
  std::cout << "build s: in-core, Embree's BVH (2 threads) after loading the cells; portico, its workers' "
               "accelerator builds added up (inside seconds). CPU s: the whole run's CPU time (portico: every "
               "process, start-up and token render included)\n";
  return csv;
}

// Same work? Deposits of portico with any number of workers are the same
// bits; the in-core tracer's differ only where a photon's path meets a
// portal or Embree's triangle test disagrees with portico's in the last bit.
// Returns 3 when portico's modes disagree, else 0.
int checkSameWork(const ModeResult* embree, const std::vector<const ModeResult*>& porticos, uint64_t photons) {
  int status = 0;
  for (const ModeResult* p : porticos) {
    const Sample& s = p->typical();
    if (s.emitted != int64_t(photons)) {
      std::cerr << fmt::format("portico: {} emitted {} photons, not {}\n", p->mode.name, s.emitted, photons);
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
  return status;
}

// Portico with N workers against 1: the ratio of the medians, and the
// median of each round's own ratio (the two modes of a round run a few
// seconds apart, so a machine whose speed drifts over minutes moves both
// alike).
void printScaling(const std::vector<const ModeResult*>& porticos) {
  for (const ModeResult* p : porticos)
    if (p->mode.workers > 1)
      for (const ModeResult* q : porticos)
        if (q->mode.workers == 1) {
          std::vector<double> rounds;
          for (size_t i = 0; i < std::min(p->samples.size(), q->samples.size()); ++i)
            if (p->samples[i].seconds > 0) rounds.push_back(q->samples[i].seconds / p->samples[i].seconds);
          std::string perRound;
          if (rounds.size() > 1)
            perRound = fmt::format(" (per round: median {:.2f}, {:.2f}-{:.2f})", median(rounds),
                                   *std::min_element(rounds.begin(), rounds.end()),
                                   *std::max_element(rounds.begin(), rounds.end()));
          std::cout << fmt::format("{} / {}: {:.2f}x{}\n", p->mode.name, q->mode.name, q->seconds() / p->seconds(),
                                   perRound);
        }
}

}  // namespace

int runBenchPipeline(const BenchPipelineOptions& requested) {
  BenchPipelineOptions options = requested;
  const std::vector<Mode> modes = parseModes(options.modes);
  const uint32_t runs = std::max<uint32_t>(1, options.runs);
  const std::optional<BuildingPreset> preset = findBuildingPreset(options.preset, options.floors);
  if (!preset)
    throw std::invalid_argument(fmt::format("unknown preset '{}' (known: {})", options.preset,
                                            fmt::join(buildingPresetNames(), ", ")));

  const TemporaryDirectory temporary("portico-bench-pipeline");
  const std::filesystem::path& work = temporary.path();
  const std::string store = prepareStore(options, *preset, work);
  const SceneStore scene = SceneStore::open(store);
  options.photons = photonsOfPass(options.photons, scene, store);
  uint64_t storeBytes = 0;
  for (const CellInfo& cell : scene.cells()) storeBytes += cell.byteCount;
  std::cout << fmt::format(
      "scene: {} cells, {} triangles, {} lights, {:.0f} MiB of cell files; {} photons, seed {}, portico accelerator "
      "'{}', worker memory {}; {} run(s) per mode, interleaved, median reported\n",
      scene.cells().size(), scene.totalTriangles(), scene.lights().size(), double(storeBytes) / (1 << 20),
      options.photons, options.seed, options.accel, options.memory, runs);
  std::cout.flush();

  const std::vector<ModeResult> results = runModes(modes, runs, scene, store, options, work);
  double embreeRate = 0;
  const ModeResult* embree = nullptr;
  std::vector<const ModeResult*> porticos;
  for (const ModeResult& r : results) {
    if (r.mode.workers == 0) {
      embree = &r;
      if (r.seconds() > 0) embreeRate = double(options.photons) / r.seconds();
    } else {
      porticos.push_back(&r);
    }
  }
  const std::string csv = printResults(results, options.photons, embreeRate);
  const int status = checkSameWork(embree, porticos, options.photons);
  printScaling(porticos);

  if (!options.csv.empty()) {
    std::ofstream out(options.csv);
    out << csv;
    if (!out) throw std::runtime_error("cannot write " + options.csv + " (check the directory exists)");
    std::cout << "wrote " << options.csv << "\n";
  }
  if (!options.plot.empty()) {
    const std::string title =
        fmt::format("{}: {} photons, {} triangles, portico --accel {}", options.preset, options.photons,
                    scene.totalTriangles(), options.accel);
    writeBarPlot(options.plot, title, results, options.photons, embreeRate);
    std::cout << "wrote " << options.plot << "\n";
  }
  return status;
}

}  // namespace portico::cli
