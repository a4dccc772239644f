// The stores, measurements and sweeps of `portico bench paper` (paper_bench.h).
#include "coordinator/cli/bench/paper_bench.h"

#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "common/scene/generator/building_generator.h"
#include "common/scene/import/building_importer.h"
#include "common/scene/generator/building_presets.h"
#include "common/scene/store/scene_store.h"

namespace portico::cli::paper {

namespace {

// The last `count` lines of a child's output (its progress lines would bury the error).
std::string lastLines(const std::string& text, size_t count) {
  size_t start = text.size();
  for (size_t lines = 0; start > 0 && lines <= count;)
    if (text[--start] == '\n') ++lines;
  return text.substr(start == 0 ? 0 : start + 1);
}

// The first line of a child's output that names the accelerator spec: the
// coordinator's or a worker's refusal ("accelerator spec 'auto': unknown ...").
std::optional<std::string> specRefusal(const std::string& output, const std::string& spec) {
  std::stringstream in(output);
  std::string line;
  while (std::getline(in, line))
    if (line.find("'" + spec + "'") != std::string::npos && line.find("accel") != std::string::npos) return line;
  return std::nullopt;
}

}  // namespace

std::string acceleratorsText(const std::map<std::string, int64_t>& accelerators) {
  std::vector<std::string> items;
  for (const auto& [spec, cells] : accelerators) items.push_back(fmt::format("{}={}", spec, cells));
  return fmt::format("{}", fmt::join(items, ";"));
}

const std::vector<std::string> kMeasurementColumns{
    "status",   "seconds",     "build_s",      "render_s",    "wall_s",  "cpu_s",       "deposits",
    "photon_crossings", "rays_traced", "ray_crossings", "cells_loaded", "leases", "load_avg", "runs",
    "seconds_all", "accelerators", "note"};

std::vector<std::string> measurementCells(const Measurement& m) {
  if (!m.ok())
    return {m.statusText(), "", "", "", "", "", "", "", "", "", "", "", fmt::format("{}", fmt::join(m.loads, " ")),
            std::to_string(m.runs.size()), "", "", m.note};
  const PipelineRunStats& s = m.typical();
  std::vector<std::string> all;
  for (const PipelineRunStats& run : m.runs) all.push_back(fmt::format("{:.3f}", run.photonSeconds));
  return {m.statusText(), fmt::format("{:.3f}", m.seconds()), fmt::format("{:.3f}", m.buildSeconds()),
          fmt::format("{:.3f}", m.renderSeconds()), fmt::format("{:.3f}", s.wallSeconds),
          fmt::format("{:.3f}", s.cpuSeconds), std::to_string(s.deposits), std::to_string(s.crossings),
          std::to_string(s.raysTraced), std::to_string(s.rayCrossings), std::to_string(s.cellsLoaded),
          std::to_string(s.leases), fmt::format("{}", fmt::join(m.loads, " ")), std::to_string(m.runs.size()),
          fmt::format("{}", fmt::join(all, " ")), acceleratorsText(s.accelerators), m.note};
}

Bench::Bench(const BenchPaperOptions& options, Scale scale) : options_(options), scale_(std::move(scale)) {
  out_ = std::filesystem::absolute(options.out);
  std::filesystem::create_directories(out_ / "stores");
}

const Measurement& Bench::measure(const Store& store, const std::string& accel, uint64_t photons,
                                  const RenderSetting& render) {
  const auto key = std::make_tuple(store.path, accel, photons, render);
  if (auto it = memo_.find(key); it != memo_.end()) return it->second;
  Measurement& m = memo_[key];
  m.photons = photons;
  for (uint32_t run = 0; run < std::max<uint32_t>(1, options_.runs); ++run)
    if (!runOnce(store, accel, photons, render, m)) break;
  return m;
}

void Bench::writeSummary() const {
  std::ofstream out(out_ / "summary.json");
  out << summary_.dump(2) << "\n";
  if (!out) throw std::runtime_error("cannot write " + (out_ / "summary.json").string());
}

const Store& Bench::store(const std::string& building, uint32_t grid) {
  const auto key = std::make_pair(building, grid);
  if (auto it = stores_.find(key); it != stores_.end()) return it->second;
  Store s;
  s.building = building;
  s.grid = grid;
  s.path = (out_ / "stores" / (grid ? fmt::format("{}-grid{}", building, grid) : building)).string();
  if (!std::filesystem::exists(std::filesystem::path(s.path) / "scene.db")) grid ? importUniform(s) : generate(s);
  const SceneStore scene = SceneStore::open(s.path);
  s.cells = scene.cells().size();
  for (const CellInfo& cell : scene.cells()) s.nonEmptyCells += cell.triangleCount > 0;
  s.triangles = scene.totalTriangles();
  s.lights = scene.lights().size();
  return stores_[key] = s;
}

void Bench::generate(const Store& s) {
  const std::optional<BuildingPreset> preset = findBuildingPreset(s.building, s.building == "tower" ? 1 : 0);
  if (!preset) throw std::invalid_argument("unknown building " + s.building);
  std::cout << fmt::format("generating {} (seed {}) into {} ...\n", s.building, options_.sceneSeed, s.path);
  std::cout.flush();
  const GeneratedBuildingStats g = generateBuilding(*preset, options_.sceneSeed, s.path);
  std::cout << fmt::format("  {} triangles, {} cells, {} lights in {:.1f} s\n", g.triangles, g.cells, g.lights,
                           g.seconds);
}

void Bench::importUniform(const Store& s) {
  const std::string source = topological(s.building).path;
  std::cout << fmt::format("cutting {} into RG={} voxel cells (scene import --grid {}) into {} ...\n", s.building,
                           s.grid, s.grid, s.path);
  std::cout.flush();
  ImportOptions options;
  options.gridResolution = s.grid;
  importBuilding({source}, s.path, options);
}

bool Bench::runOnce(const Store& store, const std::string& accel, uint64_t photons, const RenderSetting& render,
                    Measurement& m) {
  PipelineRunSpec spec;
  spec.store = store.path;
  spec.workers = options_.workers;
  spec.photons = photons;
  spec.seed = options_.seed;
  spec.spp = render.spp, spec.gather = render.gather, spec.width = render.width, spec.height = render.height;
  spec.accel = accel;
  spec.memory = options_.memory;
  spec.timeoutSeconds = scale_.timeoutSeconds;
  m.loads.push_back(loadAverage());
  const std::string what = fmt::format("[{}] {} {} {} photons{}", ++runCount_, store.label(), accel, photons,
                                       render.gather ? fmt::format(", render {}x{} gather {}", render.width,
                                                                   render.height, render.gather)
                                                     : "");
  try {
    const PipelineRunStats stats = runPipeline(spec, work_.path(), fmt::format("run-{}", runCount_));
    m.runs.push_back(stats);
    std::cout << fmt::format("{}: photons {:.2f} s (builds {:.2f} s){} load {}\n", what, stats.photonSeconds,
                             stats.buildSeconds,
                             render.gather ? fmt::format(", render {:.2f} s", stats.renderSeconds) : "",
                             m.loads.back());
    std::cout.flush();
    return true;
  } catch (const PipelineRunError& e) {
    // A spec the pipeline refuses (`auto` before it exists) is not an error
    // of the bench: the experiment shows it as unavailable.
    if (const auto refusal = specRefusal(e.output(), accel)) {
      m.status = Measurement::Status::Unavailable;
      m.note = *refusal;
    } else {
      m.status = Measurement::Status::Failed;
      const std::string what = e.what();
      m.note = what.substr(0, what.find('\n'));   // "portico render ... failed (status N | stopped after S s)"
      std::cerr << m.note << "; the end of its output:\n" << lastLines(e.output(), 6);
    }
    m.runs.clear();
    std::cout << fmt::format("{}: {} ({})\n", what, m.statusText(), m.note);
    std::cout.flush();
    return false;
  }
}

std::vector<SweepPoint> gridSweep(Bench& bench, const std::string& building) {
  std::vector<SweepPoint> points;
  const uint64_t photons = bench.photons(building, bench.scale().photonsPerLight);
  for (int r : bench.scale().gridResolutions) {
    const std::string spec = fmt::format("grid:res={}", r);
    points.push_back({spec, &bench.measure(bench.topological(building), spec, photons)});
  }
  return points;
}

const SweepPoint* fastest(const std::vector<SweepPoint>& points) {
  const SweepPoint* best = nullptr;
  for (const SweepPoint& p : points)
    if (p.m->ok() && (!best || p.m->seconds() < best->m->seconds())) best = &p;
  return best;
}

std::vector<SweepPoint> kdSweep(Bench& bench, const Store& store, uint64_t photons) {
  std::vector<SweepPoint> points;
  for (const std::string& spec : kKdHeuristics) points.push_back({spec, &bench.measure(store, spec, photons)});
  return points;
}

std::string scaleNote(const Bench& bench, uint64_t perLight) {
  return fmt::format("{} photons/light (paper {})", perLight,
                     perLight == bench.scale().fewPhotonsPerLight ? kPaperFewPhotonsPerLight : kPaperPhotonsPerLight);
}

}  // namespace portico::cli::paper
