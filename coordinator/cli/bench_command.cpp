// `portico bench accel`: build time and single-thread tracing speed of the
// per-cell accelerators on furnished cells of chosen triangle counts, with
// Embree measured in the same run as the yardstick.
//
// For each size: a furnished hall of exactly that many triangles
// (generateFurnishedHall: the count comes from tessellated furniture), two
// ray sets (photon-like: origins on surfaces chosen by area, cosine-
// distributed about the front normal; camera-like: from one point above the
// furniture through a grid of directions, like a pinhole camera), and for
// each structure: the median of `runs` builds, then per ray set a warm-up
// pass and the median of `runs` timed passes, all on this one thread with
// flush-to-zero on. Ratios to Embree compare numbers taken minutes apart on
// the same machine; absolute numbers move with the machine's load.
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
#include "common/scene/furnished_hall.h"
#include "coordinator/cli/bench_plot.h"
#include "coordinator/cli/commands.h"

namespace portico::cli {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n == 0 ? 0.0 : (n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]));
}

// "1000,10k,1M" -> {1000, 10000, 1000000}.
std::vector<size_t> parseSizes(const std::string& text) {
  std::vector<size_t> sizes;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = std::min(text.find(',', start), text.size());
    const std::string item = text.substr(start, comma - start);
    char* end = nullptr;
    const double value = std::strtod(item.c_str(), &end);
    double scale = 1;
    const std::string suffix = end ? std::string(end) : "";
    if (suffix == "k" || suffix == "K") scale = 1e3;
    else if (suffix == "m" || suffix == "M") scale = 1e6;
    else if (!suffix.empty()) scale = 0;
    if (item.empty() || end == item.c_str() || scale == 0 || !(value * scale >= 12) || value * scale > 4e9)
      throw std::invalid_argument("--sizes: '" + item +
                                  "' is not a triangle count from 12 to 4e9 (write e.g. 1000,10k,1M)");
    sizes.push_back(size_t(std::llround(value * scale)));
    start = comma + 1;
  }
  return sizes;
}

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
// Rays

constexpr float kSurfaceOffset = 1e-4f;  // metres: photon origins leave their surface by this much

// Photon-like rays: a surface point chosen by area (uniform over the cell's
// surface), leaving it on the front side with a cosine-distributed direction.
std::vector<Ray> photonRays(const MeshView& mesh, size_t count, uint64_t seed) {
  std::vector<double> cumulativeArea(mesh.triangleCount);
  double total = 0;
  for (uint32_t t = 0; t < mesh.triangleCount; ++t) {
    total += 0.5 * double(length(mesh.geometricNormal(t)));
    cumulativeArea[t] = total;
  }
  std::vector<Ray> rays;
  rays.reserve(count);
  for (uint64_t i = 0; i < count; ++i) {
    const auto u = [&](uint32_t dimension) { return randomUniform(seed, RandomStream::Photon, i, 0, dimension); };
    const double pick = double(u(0)) * total;
    const uint32_t primitive = uint32_t(std::min<size_t>(
        size_t(std::upper_bound(cumulativeArea.begin(), cumulativeArea.end(), pick) - cumulativeArea.begin()),
        mesh.triangleCount - 1));
    Vec3 v0, v1, v2;
    mesh.triangle(primitive, v0, v1, v2);
    const float r = std::sqrt(u(1)), s = u(2);
    const Vec3 point = v0 * (1 - r) + v1 * (r * (1 - s)) + v2 * (r * s);
    const Vec3 normal = normalize(mesh.geometricNormal(primitive));
    Vec3 tangent, bitangent;
    orthonormalBasis(normal, tangent, bitangent);
    const float radius = std::sqrt(u(3)), phi = 2 * kPi * u(4);
    const Vec3 direction = tangent * (radius * std::cos(phi)) + bitangent * (radius * std::sin(phi)) +
                           normal * std::sqrt(std::max(0.0f, 1 - radius * radius));
    rays.push_back(Ray{point + normal * kSurfaceOffset, direction});
  }
  return rays;
}

// Camera-like rays: from the hall's eye point (above the furniture), looking
// diagonally across the hall and 30 degrees down, through a 16:9 grid of
// directions spanning 100 degrees horizontally; row by row.
std::vector<Ray> cameraRays(const FurnishedHall& hall, size_t count) {
  const Vec3 eye = hall.eye;
  const Vec3 across = normalize(hall.cell.bounds.hi - hall.cell.bounds.lo) * Vec3(1, 0, 1);
  const float pitch = -30.0f * kPi / 180.0f;
  const Vec3 forward = normalize(normalize(across) * std::cos(pitch) + Vec3(0, std::sin(pitch), 0));
  const Vec3 right = normalize(cross(forward, Vec3(0, 1, 0)));
  const Vec3 up = cross(right, forward);
  const float halfWidth = std::tan(50.0f * kPi / 180.0f);
  const size_t columns = std::max<size_t>(1, size_t(std::llround(std::sqrt(double(count) * 16.0 / 9.0))));
  const size_t rows = (count + columns - 1) / columns;
  const float halfHeight = halfWidth * float(rows) / float(columns);
  std::vector<Ray> rays;
  rays.reserve(count);
  for (size_t i = 0; i < count; ++i) {
    const float x = (2 * (float(i % columns) + 0.5f) / float(columns) - 1) * halfWidth;
    const float y = (1 - 2 * (float(i / columns) + 0.5f) / float(rows)) * halfHeight;
    rays.push_back(Ray{eye, normalize(forward + right * x + up * y)});
  }
  return rays;
}

// ---------------------------------------------------------------------------
// Measurements

struct RaySet {
  std::string kind;  // "photon", "camera"
  std::vector<Ray> rays;
};

struct TraceResult {
  double mraysPerSecond = 0;
  uint64_t hits = 0;
  uint64_t differing = 0;  // rays whose hit differs from the reference structure's
  std::vector<Hit> hitList;
};

struct StructureResult {
  std::string spec;
  bool isEmbree = false;
  AcceleratorStats stats;
  double buildMs = 0;
  std::vector<TraceResult> traces;  // one per ray set
};

TraceResult trace(const Accelerator& accelerator, const std::vector<Ray>& rays, uint32_t runs) {
  TraceResult result;
  result.hitList.resize(rays.size());
  // Warm-up: caches, page faults, branch predictors.
  for (size_t i = 0; i < std::min<size_t>(rays.size(), 10000); ++i) result.hitList[i] = accelerator.intersect(rays[i]);
  std::vector<double> seconds;
  for (uint32_t run = 0; run < runs; ++run) {
    const auto start = Clock::now();
    for (size_t i = 0; i < rays.size(); ++i) result.hitList[i] = accelerator.intersect(rays[i]);
    seconds.push_back(secondsSince(start));
  }
  const double time = median(seconds);
  result.mraysPerSecond = time > 0 ? double(rays.size()) / time * 1e-6 : 0.0;
  for (const Hit& hit : result.hitList) result.hits += hit.found();
  return result;
}

// Builds `runs` times (once when a build takes over 20 s) and keeps the last.
std::unique_ptr<Accelerator> build(const AcceleratorSpec& spec, const MeshView& mesh, uint32_t runs,
                                   double& medianMs) {
  std::unique_ptr<Accelerator> accelerator;
  std::vector<double> milliseconds;
  for (uint32_t run = 0; run < runs; ++run) {
    accelerator.reset();  // free the previous one first: measure one structure's memory at a time
    const auto start = Clock::now();
    accelerator = buildAccelerator(spec, mesh);
    milliseconds.push_back(secondsSince(start) * 1e3);
    if (milliseconds.back() > 20000) break;
  }
  medianMs = median(milliseconds);
  return accelerator;
}

// A CSV field, quoted when it holds a comma or a quote (specs with parameters do).
std::string csvField(const std::string& text) {
  if (text.find_first_of(",\"") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

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

}  // namespace

int runBenchAccel(const BenchAccelOptions& options) {
  const std::vector<size_t> sizes = parseSizes(options.sizes);
  if (options.rays == 0) throw std::invalid_argument("--rays must be at least 1");
  const uint32_t runs = std::max<uint32_t>(1, options.runs);

  // Specs: unknown kinds are skipped (another build may have them), bad
  // parameters of known kinds are an error.
  std::vector<AcceleratorSpec> specs;
  const std::vector<std::string_view> known = acceleratorKinds();
  for (const std::string& text : splitSpecs(options.specs)) {
    const AcceleratorSpec spec = parseAcceleratorSpec(text);
    if (std::find(known.begin(), known.end(), spec.kind) == known.end()) {
      std::cout << fmt::format("skipping {}: accelerator kind '{}' is not registered in this build\n", text,
                               spec.kind);
      continue;
    }
    validateAcceleratorSpec(spec);
    specs.push_back(spec);
  }
  if (specs.empty()) throw std::invalid_argument("--specs: no registered accelerator to measure");

  // Builds on one thread like portico's own, unless asked otherwise.
  const std::string embreeConfig = options.embreeThreads > 0 ? fmt::format("threads={}", options.embreeThreads) : "";
  if (!configureEmbreeDevice(embreeConfig))
    std::cout << "note: the Embree device was made earlier; --embree-threads is not applied\n";
  const FlushDenormalsScope flushDenormals;
  // Make Embree's device (and its thread pool) now, so that no build time includes it.
  for (const AcceleratorSpec& spec : specs)
    if (spec.kind == "embree") {
      const float triangle[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0};
      const uint32_t indices[] = {0, 1, 2};
      buildAccelerator(spec, MeshView{triangle, 3, indices, 1, 1});
      break;
    }

  std::cout << fmt::format(
      "portico bench accel: {} photon + {} camera rays per size, single thread, median of {} runs; "
      "builds single-threaded{}\n",
      options.rays, options.rays, runs,
      options.embreeThreads == 1 ? " (Embree too: threads=1)"
                                 : fmt::format(" (Embree: {})", embreeConfig.empty() ? "all cores" : embreeConfig));
  std::cout << "columns: build ms (x embree), MiB, Mrays/s (x embree) per ray kind; check: hits against the first "
               "portico structure (bit-exact), Embree by primitive\n";

  std::string csv =
      "structure,triangles,ray_kind,rays,build_ms,mrays_per_s,ratio_to_embree,build_ratio_to_embree,bytes,nodes,"
      "leaves,max_depth,average_depth,hits,differing_from_reference\n";
  std::map<std::string, std::vector<std::pair<double, double>>> buildSeries;                 // spec -> (n, ms)
  std::map<std::pair<std::string, std::string>, std::vector<std::pair<double, double>>> raySeries;  // (spec, kind)
  std::vector<std::string> order;
  for (const AcceleratorSpec& spec : specs) order.push_back(spec.text);
  bool anyPorticoMismatch = false;
  size_t nameWidth = 12;
  for (const std::string& text : order) nameWidth = std::max(nameWidth, text.size());

  for (size_t size : sizes) {
    const auto generateStart = Clock::now();
    FurnishedHall hall = generateFurnishedHall(size, options.seed);
    // One readable float after the last vertex, as a cell file can promise:
    // Embree may share the vertices.
    const size_t vertexCount = hall.cell.positions.size() / 3;
    hall.cell.positions.push_back(0.0f);
    MeshView mesh;
    mesh.positions = hall.cell.positions.data();
    mesh.vertexCount = vertexCount;
    mesh.indices = hall.cell.indices.data();
    mesh.triangleCount = hall.cell.indices.size() / 3;
    mesh.positionsPaddingFloats = 1;
    std::vector<RaySet> raySets;
    raySets.push_back({"photon", photonRays(mesh, options.rays, options.seed)});
    raySets.push_back({"camera", cameraRays(hall, options.rays)});
    const Vec3 extent = hall.cell.bounds.diagonal();
    std::cout << fmt::format(
        "\n{} triangles: hall {:.0f} x {:.0f} x {:.0f} m, {} furnished zones, furniture tessellation {}x{} "
        "(made in {:.1f} s)\n",
        mesh.triangleCount, extent.x, extent.z, extent.y, hall.zones, hall.tessellation, hall.tessellation,
        secondsSince(generateStart));
    std::cout << fmt::format("{:<{}} {:>10} {:>8} {:>8} {:>9} {:>8} {:>9} {:>8}  {}\n", "structure", nameWidth,
                             "build ms", "x embree", "MiB", "photon", "x embree", "camera", "x embree", "check");
    std::cout.flush();

    std::vector<StructureResult> results;
    const StructureResult* reference = nullptr;
    for (const AcceleratorSpec& spec : specs) {
      StructureResult result;
      result.spec = spec.text;
      result.isEmbree = spec.kind == "embree";
      std::unique_ptr<Accelerator> accelerator = build(spec, mesh, runs, result.buildMs);
      result.stats = accelerator->stats();
      for (const RaySet& set : raySets) result.traces.push_back(trace(*accelerator, set.rays, runs));
      accelerator.reset();
      results.push_back(std::move(result));
    }
    for (const StructureResult& result : results)
      if (!result.isEmbree) {
        reference = &result;
        break;
      }
    // Check every structure against the reference; then hits can go.
    for (StructureResult& result : results) {
      if (!reference || &result == reference) continue;
      for (size_t k = 0; k < raySets.size(); ++k) {
        const std::vector<Hit>& expected = reference->traces[k].hitList;
        const std::vector<Hit>& got = result.traces[k].hitList;
        for (size_t i = 0; i < got.size(); ++i)
          result.traces[k].differing += result.isEmbree ? got[i].primitive != expected[i].primitive
                                                        : std::memcmp(&got[i], &expected[i], sizeof(Hit)) != 0;
      }
    }

    const StructureResult* embree = nullptr;
    for (const StructureResult& result : results)
      if (result.isEmbree) embree = &result;
    for (const StructureResult& result : results) {
      std::string check;
      if (&result == reference) {
        check = "reference";
      } else if (reference) {
        uint64_t differing = 0, total = 0;
        for (const TraceResult& t : result.traces) differing += t.differing, total += t.hitList.size();
        if (result.isEmbree)
          check = fmt::format("{:.3f}% other primitive", 100.0 * double(differing) / double(total));
        else
          check = differing == 0 ? "identical" : fmt::format("{} rays DIFFER", differing);
        if (!result.isEmbree && differing > 0) anyPorticoMismatch = true;
      }
      std::cout << fmt::format("{:<{}} {:>10.2f} {:>8} {:>8.1f} {:>9.2f} {:>8} {:>9.2f} {:>8}  {}\n", result.spec,
                               nameWidth, result.buildMs, embree ? ratio(result.buildMs, embree->buildMs) : "",
                               double(result.stats.bytes) / (1 << 20), result.traces[0].mraysPerSecond,
                               embree ? ratio(result.traces[0].mraysPerSecond, embree->traces[0].mraysPerSecond) : "",
                               result.traces[1].mraysPerSecond,
                               embree ? ratio(result.traces[1].mraysPerSecond, embree->traces[1].mraysPerSecond) : "",
                               check);
      buildSeries[result.spec].push_back({double(mesh.triangleCount), result.buildMs});
      for (size_t k = 0; k < raySets.size(); ++k) {
        const TraceResult& t = result.traces[k];
        raySeries[{result.spec, raySets[k].kind}].push_back({double(mesh.triangleCount), t.mraysPerSecond});
        csv += fmt::format("{},{},{},{},{:.3f},{:.4f},{},{},{},{},{},{},{:.3f},{},{}\n", csvField(result.spec),
                           mesh.triangleCount, raySets[k].kind, raySets[k].rays.size(), result.buildMs,
                           t.mraysPerSecond, embree ? ratio(t.mraysPerSecond, embree->traces[k].mraysPerSecond) : "",
                           embree ? ratio(result.buildMs, embree->buildMs) : "", result.stats.bytes,
                           result.stats.nodes, result.stats.leaves, result.stats.maxDepth, result.stats.averageDepth,
                           t.hits, &result == reference ? 0 : t.differing);
      }
    }
    std::cout.flush();
    // The CSV is rewritten after every size, so a long run keeps what it measured.
    if (!options.csv.empty()) {
      std::ofstream out(options.csv);
      out << csv;
      if (!out) throw std::runtime_error("cannot write " + options.csv + " (check the directory exists)");
    }
  }
  if (!options.csv.empty()) std::cout << "\nwrote " << options.csv << "\n";

  if (!options.plot.empty()) {
    Palette palette;
    PlotPanel buildPanel{"Build time", "triangles", "ms", true, true, {}};
    PlotPanel rayPanel{"Mrays/s, one thread (solid: photon, dashed: camera)", "triangles", "Mrays/s", true, false, {}};
    for (const std::string& spec : order) {
      PlotSeries series{spec, palette(spec), false, {}, {}};
      for (const auto& [n, ms] : buildSeries[spec]) series.x.push_back(n), series.y.push_back(ms);
      buildPanel.series.push_back(series);
      for (const char* kind : {"photon", "camera"}) {
        PlotSeries rays{std::string(kind) == "photon" ? spec : "", palette(spec), std::string(kind) == "camera", {}, {}};
        for (const auto& [n, speed] : raySeries[{spec, kind}]) rays.x.push_back(n), rays.y.push_back(speed);
        rayPanel.series.push_back(rays);
      }
    }
    writePlotPng(options.plot, {buildPanel, rayPanel}, 700, 500);
    std::cout << "wrote " << options.plot << "\n";
  }
  if (anyPorticoMismatch) {
    std::cerr << "portico: some of portico's structures returned hits that differ from the reference: a bug\n";
    return 3;
  }
  return 0;
}

}  // namespace portico::cli
