// `portico bench accel`: build time and single-thread tracing speed of the
// per-cell accelerators on furnished cells of chosen triangle counts, with
// Embree measured in the same run as the yardstick.
//
// For each size: a furnished hall of exactly that many triangles
// (generateFurnishedHall: the count comes from tessellated furniture), two
// ray sets (photon-like: origins on surfaces chosen by area, cosine-
// distributed about the front normal; camera-like: from one point above the
// furniture through a grid of directions, like a pinhole camera), and for
// each structure: the median of `runs` builds; then per ray set, with every
// structure built, a warm-up pass of each and `runs` rounds of timed passes,
// one per structure in turn (each after a short warm-up of its own), the
// median per structure; all on this one thread with flush-to-zero on. Taken
// in turn, the passes of two structures are seconds apart, so their ratio
// holds while the machine's load moves; absolute numbers move with it.
#include "coordinator/cli/bench/bench_accel.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/accel/accelerator.h"
#include "common/accel/embree_accelerator.h"
#include "common/rng.h"
#include "common/scene/generator/furnished_hall.h"
#include "coordinator/cli/bench/accel_measure.h"
#include "coordinator/cli/bench/bench_plot.h"
#include "common/util/csv_field.h"

namespace portico::cli {

namespace {

// Specs are separated by commas, but a spec's own parameters are written
// with commas too ("hgrid:res=16,max=64"): an item of the form name=value
// without a ':' belongs to the spec before it. ';' always separates.
std::vector<std::string> splitSpecs(const std::string& text) {
  std::vector<std::string> specs;
  std::string current;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t end = std::min(text.find_first_of(",;", start), text.size());
    const std::string item = text.substr(start, end - start);
    const bool parameter = item.find('=') != std::string::npos && item.find(':') == std::string::npos;
    if (parameter && !current.empty()) {
      current += "," + item;
    } else {
      if (!current.empty()) specs.push_back(current);
      current = item;
    }
    if (end < text.size() && text[end] == ';') {
      if (!current.empty()) specs.push_back(current);
      current.clear();
    }
    start = end + 1;
  }
  if (!current.empty()) specs.push_back(current);
  return specs;
}

// ---------------------------------------------------------------------------
// Measurements

struct RaySet {
  std::string kind;  // "photon", "camera"
  std::vector<Ray> rays;
};

struct StructureResult {
  std::string spec;
  bool isEmbree = false;
  AcceleratorStats stats;
  double buildMs = 0;
  std::vector<TraceResult> traces;  // one per ray set
};

std::string ratio(double value, double reference) {
  return reference > 0 && value > 0 ? fmt::format("{:.2f}", value / reference) : "";
}

struct Palette {
  std::map<std::string, std::array<uint8_t, 3>> assigned;
  std::array<uint8_t, 3> operator()(const std::string& spec) {
    static constexpr std::array<uint8_t, 3> kColors[] = {{31, 119, 180}, {255, 127, 14}, {44, 160, 44},
                                                         {214, 39, 40},  {148, 103, 189}, {0, 0, 0},
                                                         {140, 86, 75},  {227, 119, 194}, {127, 127, 127}};
    if (spec == "embree") return {0, 0, 0};
    auto found = assigned.find(spec);
    if (found != assigned.end()) return found->second;
    std::array<uint8_t, 3> color = kColors[assigned.size() % 9];
    if (color == std::array<uint8_t, 3>{0, 0, 0}) color = kColors[8];
    assigned[spec] = color;
    return color;
  }
};

// The specs to measure: unknown kinds are skipped (another build may have
// them), bad parameters of known kinds are an error.
std::vector<AcceleratorSpec> registeredSpecs(const std::string& text) {
  std::vector<AcceleratorSpec> specs;
  const std::vector<std::string_view> known = acceleratorKinds();
  for (const std::string& item : splitSpecs(text)) {
    const AcceleratorSpec spec = parseAcceleratorSpec(item);
    if (std::find(known.begin(), known.end(), spec.kind) == known.end()) {
      std::cout << fmt::format("skipping {}: accelerator kind '{}' is not registered in this build\n", item,
                               spec.kind);
      continue;
    }
    validateAcceleratorSpec(spec);
    specs.push_back(spec);
  }
  if (specs.empty()) throw std::invalid_argument("--specs: no registered accelerator to measure");
  return specs;
}

// Builds on one thread like portico's own, unless asked otherwise; the
// device (and its thread pool) is made now, so that no build time includes
// it. Returns the device's configuration.
std::string prepareEmbree(const std::vector<AcceleratorSpec>& specs, uint32_t embreeThreads) {
  const std::string embreeConfig = embreeThreads > 0 ? fmt::format("threads={}", embreeThreads) : "";
  if (!configureEmbreeDevice(embreeConfig))
    std::cout << "note: the Embree device was made earlier; --embree-threads is not applied\n";
  for (const AcceleratorSpec& spec : specs)
    if (spec.kind == "embree") {
      const float triangle[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0};
      const uint32_t indices[] = {0, 1, 2};
      buildAccelerator(spec, MeshView{triangle, 3, indices, 1, 1});
      break;
    }
  return embreeConfig;
}

// One size's hall, ray sets and structures, measured.
struct SizeResults {
  size_t triangles = 0;
  std::vector<RaySet> raySets;
  std::vector<StructureResult> structures;
  const StructureResult* reference = nullptr;  // the first of portico's own
  const StructureResult* embree = nullptr;     // the yardstick
};

// Every structure against the reference: bit-exact hits for portico's, the
// same primitive for Embree's.
void compareWithReference(SizeResults& size) {
  for (StructureResult& result : size.structures) {
    if (!size.reference || &result == size.reference) continue;
    for (size_t k = 0; k < size.raySets.size(); ++k) {
      const std::vector<Hit>& expected = size.reference->traces[k].hitList;
      const std::vector<Hit>& got = result.traces[k].hitList;
      for (size_t i = 0; i < got.size(); ++i)
        result.traces[k].differing += result.isEmbree ? got[i].primitive != expected[i].primitive
                                                      : std::memcmp(&got[i], &expected[i], sizeof(Hit)) != 0;
    }
  }
}

// Builds every structure on the mesh, in the order given, then traces each
// ray set with all of them, their timed passes in turn.
std::vector<StructureResult> measureStructures(const MeshView& mesh, const std::vector<RaySet>& raySets,
                                               const std::vector<AcceleratorSpec>& specs, uint32_t runs) {
  std::vector<StructureResult> results;
  std::vector<std::unique_ptr<Accelerator>> built;
  for (const AcceleratorSpec& spec : specs) {
    StructureResult result;
    result.spec = spec.text;
    result.isEmbree = spec.kind == "embree";
    built.push_back(timedBuild(spec, mesh, runs, result.buildMs));
    result.stats = built.back()->stats();
    results.push_back(std::move(result));
  }
  std::vector<const Accelerator*> accelerators;
  for (const auto& accelerator : built) accelerators.push_back(accelerator.get());
  for (const RaySet& set : raySets) {
    std::vector<TraceResult> traces = traceRaysInterleaved(accelerators, set.rays, runs);
    for (size_t k = 0; k < results.size(); ++k) results[k].traces.push_back(std::move(traces[k]));
  }
  return results;
}

// A hall of `size` triangles, its two ray sets (photon, camera), and every
// structure measured on them; the hall's line and the table's header are
// printed before the measurements start.
SizeResults measureSize(size_t size, const std::vector<AcceleratorSpec>& specs, const BenchAccelOptions& options,
                        uint32_t runs, size_t nameWidth) {
  SizeResults results;
  const auto generateStart = Clock::now();
  FurnishedHall hall = generateFurnishedHall(size, options.seed);
  const MeshView mesh = hallMesh(hall);
  results.triangles = mesh.triangleCount;
  results.raySets.push_back({"photon", photonRays(mesh, options.rays, options.seed)});
  results.raySets.push_back({"camera", cameraRays(hall, options.rays)});
  const Vec3 extent = hall.cell.bounds.diagonal();
  std::cout << fmt::format(
      "\n{} triangles: hall {:.0f} x {:.0f} x {:.0f} m, {} furnished zones, furniture tessellation {}x{} "
      "(made in {:.1f} s)\n",
      mesh.triangleCount, extent.x, extent.z, extent.y, hall.zones, hall.tessellation, hall.tessellation,
      secondsSince(generateStart));
  std::cout << fmt::format("{:<{}} {:>10} {:>8} {:>8} {:>9} {:>8} {:>9} {:>8}  {}\n", "structure", nameWidth,
                           "build ms", "x embree", "MiB", "photon", "x embree", "camera", "x embree", "check");
  std::cout.flush();

  results.structures = measureStructures(mesh, results.raySets, specs, runs);
  for (const StructureResult& result : results.structures)
    if (!result.isEmbree) {
      results.reference = &result;
      break;
    }
  compareWithReference(results);
  // The yardstick: plain `embree` (medium quality, as the targets are
  // quoted against), else the first Embree variant measured.
  const auto isYardstick = [](const StructureResult& r) { return r.spec == "embree" || r.spec == "embree:medium"; };
  for (const StructureResult& result : results.structures)
    if (result.isEmbree && (!results.embree || (isYardstick(result) && !isYardstick(*results.embree))))
      results.embree = &result;
  return results;
}

// What the run has measured so far: the CSV's text and the plot's series.
struct AccelReport {
  std::string csv =
      "structure,triangles,ray_kind,rays,build_ms,mrays_per_s,ratio_to_embree,build_ratio_to_embree,bytes,nodes,"
      "leaves,max_depth,average_depth,hits,differing_from_reference\n";
  std::map<std::string, std::vector<std::pair<double, double>>> buildSeries;                 // spec -> (n, ms)
  std::map<std::pair<std::string, std::string>, std::vector<std::pair<double, double>>> raySeries;  // (spec, kind)
  bool anyPorticoMismatch = false;
};

// The check column: how a structure's hits compare with the reference's.
std::string checkText(const SizeResults& size, const StructureResult& result, AccelReport& report) {
  if (&result == size.reference) return "reference";
  if (!size.reference) return "";
  uint64_t differing = 0, total = 0;
  for (const TraceResult& t : result.traces) differing += t.differing, total += t.hitList.size();
  if (result.isEmbree) return fmt::format("{:.3f}% other primitive", 100.0 * double(differing) / double(total));
  if (differing > 0) report.anyPorticoMismatch = true;
  return differing == 0 ? "identical" : fmt::format("{} rays DIFFER", differing);
}

// One size's table on stdout, and its rows and points in the report.
void reportSize(const SizeResults& size, size_t nameWidth, AccelReport& report) {
  const StructureResult* embree = size.embree;
  for (const StructureResult& result : size.structures) {
    const std::string check = checkText(size, result, report);
    std::cout << fmt::format("{:<{}} {:>10.2f} {:>8} {:>8.1f} {:>9.2f} {:>8} {:>9.2f} {:>8}  {}\n", result.spec,
                             nameWidth, result.buildMs, embree ? ratio(result.buildMs, embree->buildMs) : "",
                             double(result.stats.bytes) / (1 << 20), result.traces[0].mraysPerSecond,
                             embree ? ratio(result.traces[0].mraysPerSecond, embree->traces[0].mraysPerSecond) : "",
                             result.traces[1].mraysPerSecond,
                             embree ? ratio(result.traces[1].mraysPerSecond, embree->traces[1].mraysPerSecond) : "",
                             check);
    report.buildSeries[result.spec].push_back({double(size.triangles), result.buildMs});
    for (size_t k = 0; k < size.raySets.size(); ++k) {
      const TraceResult& t = result.traces[k];
      report.raySeries[{result.spec, size.raySets[k].kind}].push_back({double(size.triangles), t.mraysPerSecond});
      report.csv += fmt::format("{},{},{},{},{:.3f},{:.4f},{},{},{},{},{},{},{:.3f},{},{}\n", csvField(result.spec),
                                size.triangles, size.raySets[k].kind, size.raySets[k].rays.size(), result.buildMs,
                                t.mraysPerSecond,
                                embree ? ratio(t.mraysPerSecond, embree->traces[k].mraysPerSecond) : "",
                                embree ? ratio(result.buildMs, embree->buildMs) : "", result.stats.bytes,
                                result.stats.nodes, result.stats.leaves, result.stats.maxDepth,
                                result.stats.averageDepth, t.hits, &result == size.reference ? 0 : t.differing);
    }
  }
  std::cout.flush();
}

void writeAccelPlot(const std::string& path, const std::vector<std::string>& order, const AccelReport& report) {
  Palette palette;
  PlotPanel buildPanel{"Build time", "triangles", "ms", true, true, {}};
  PlotPanel rayPanel{"Mrays/s, one thread (solid: photon, dashed: camera)", "triangles", "Mrays/s", true, false, {}};
  for (const std::string& spec : order) {
    PlotSeries series{spec, palette(spec), false, {}, {}};
    if (auto found = report.buildSeries.find(spec); found != report.buildSeries.end())
      for (const auto& [n, ms] : found->second) series.x.push_back(n), series.y.push_back(ms);
    buildPanel.series.push_back(series);
    for (const char* kind : {"photon", "camera"}) {
      PlotSeries rays{std::string(kind) == "photon" ? spec : "", palette(spec), std::string(kind) == "camera", {}, {}};
      if (auto found = report.raySeries.find({spec, kind}); found != report.raySeries.end())
        for (const auto& [n, speed] : found->second) rays.x.push_back(n), rays.y.push_back(speed);
      rayPanel.series.push_back(rays);
    }
  }
  writePlotPng(path, {buildPanel, rayPanel}, 700, 500);
}

}  // namespace

int runBenchAccel(const BenchAccelOptions& options) {
  const std::vector<size_t> sizes = parseTriangleCounts(options.sizes);
  if (options.rays == 0) throw std::invalid_argument("--rays must be at least 1");
  const uint32_t runs = std::max<uint32_t>(1, options.runs);
  const std::vector<AcceleratorSpec> specs = registeredSpecs(options.specs);
  const FlushDenormalsScope flushDenormals;
  const std::string embreeConfig = prepareEmbree(specs, options.embreeThreads);

  std::cout << fmt::format(
      "portico bench accel: {} photon + {} camera rays per size, single thread, median of {} runs; "
      "builds single-threaded{}\n",
      options.rays, options.rays, runs,
      options.embreeThreads == 1 ? " (Embree too: threads=1)"
                                 : fmt::format(" (Embree: {})", embreeConfig.empty() ? "all cores" : embreeConfig));
  std::cout << "columns: build ms (x embree), MiB, Mrays/s (x embree) per ray kind; check: hits against the first "
               "portico structure (bit-exact), Embree by primitive\n";

  std::vector<std::string> order;
  for (const AcceleratorSpec& spec : specs) order.push_back(spec.text);
  size_t nameWidth = 12;
  for (const std::string& text : order) nameWidth = std::max(nameWidth, text.size());
  AccelReport report;
  for (size_t size : sizes) {
    const SizeResults results = measureSize(size, specs, options, runs, nameWidth);
    reportSize(results, nameWidth, report);
    // The CSV is rewritten after every size, so a long run keeps what it measured.
    if (!options.csv.empty()) {
      std::ofstream out(options.csv);
      out << report.csv;
      if (!out) throw std::runtime_error("cannot write " + options.csv + " (check the directory exists)");
    }
  }
  if (!options.csv.empty()) std::cout << "\nwrote " << options.csv << "\n";
  if (!options.plot.empty()) {
    writeAccelPlot(options.plot, order, report);
    std::cout << "wrote " << options.plot << "\n";
  }
  if (report.anyPorticoMismatch) {
    std::cerr << "portico: some of portico's structures returned hits that differ from the reference: a bug\n";
    return 3;
  }
  return 0;
}

}  // namespace portico::cli
