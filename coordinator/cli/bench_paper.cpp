// `portico bench paper`: the experiments of Fradin & Meneveaux (2006) §6,
// each measurement a real `portico render` child process (coordinator and
// workers) over a generated building, timed by the job's own statistics
// (time_ms.photons: submission to the last photon Result, cell loads and
// accelerator builds included, as the paper's "cumulative time for
// initializing ... and propagating photons"). docs/paper-benchmark.md.
//
// Every measurement goes through one memo (Bench::measure), so experiments
// that need the same run (the best grid of Fig. 5 in Fig. 9, the kd-trees of
// Fig. 8 in Fig. 9 and in auto_vs_fixed) share it and can also run alone.
#include "coordinator/cli/bench_paper.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "common/accel/accelerator.h"
#include "common/scene/generator/building_generator.h"
#include "common/scene/import/building_importer.h"
#include "common/scene/generator/building_presets.h"
#include "common/scene/store/cell_geometry.h"
#include "common/scene/store/scene_store.h"
#include "common/util/temporary_directory.h"
#include "coordinator/cli/accel_measure.h"
#include "coordinator/cli/bench_plot.h"
#include "coordinator/cli/csv_field.h"
#include "coordinator/cli/pipeline_run.h"

namespace portico::cli {

namespace {

namespace fs = std::filesystem;
using Rgb = std::array<uint8_t, 3>;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
const std::vector<std::string> kKdHeuristics{"kd:median", "kd:sah", "kd:bbox"};
const std::vector<std::string> kExperiments{"fig4_5_grid_resolution", "fig6_hgrid_init",
                                            "table3_kd_depth",        "fig7_8_kd_heuristics",
                                            "fig9_best_topological",  "table4_uniform_cells",
                                            "fig11_topological_vs_uniform", "auto_vs_fixed"};

// ---------------------------------------------------------------------------
// Scale: what each mode runs. The paper shot 50 000 photons per light on a
// 2006 dual Xeon; here the counts are cut so that the default finishes in
// under an hour and --quick in a few minutes on a 2-core machine.

struct Scale {
  std::string mode;
  std::vector<std::string> buildings;   // Fig. 5, Table 3, Figs. 7-9, auto_vs_fixed
  std::string floorBuilding;            // Figs. 4 and 6 ("one floor of Tower101")
  bool floorInComparisons = false;      // the floor also in Figs. 7-9 and auto_vs_fixed
  std::vector<int> gridResolutions;
  int hgridResolution = 64;             // Fig. 6: the paper's 64^3 top grid
  std::vector<int> hgridMax;
  uint64_t photonsPerLight = 0, fewPhotonsPerLight = 0;
  std::map<std::string, std::vector<uint32_t>> uniformGrids;   // Table 4: building -> RG values
  uint32_t renderWidth = 0, renderHeight = 0, renderGather = 4;
  std::string renderAccel = "kd:sah";   // the paper's best structure for final gathering
  double timeoutSeconds = 600;
};

Scale defaultScale() {
  Scale s;
  s.mode = "default";
  s.buildings = {"l-shape", "z-building", "octagon", "soda-hall"};
  s.floorBuilding = "tower";
  s.floorInComparisons = true;
  s.gridResolutions = {8, 16, 24, 32, 48, 64, 96, 128};
  // Below 8 the tower floor's hgrid:res=64 builds for minutes (max=4: over 3 minutes here), for a
  // point the curve already shows: initialisation grows as max falls.
  s.hgridMax = {8, 16, 32, 64, 128, 256, 512};
  s.photonsPerLight = 1000;
  s.fewPhotonsPerLight = 400;   // 20K : 50K as in the paper
  s.uniformGrids = {{"l-shape", {6, 10}}, {"octagon", {8, 12}}, {"soda-hall", {8, 12}}};
  s.renderWidth = 128, s.renderHeight = 96;
  s.timeoutSeconds = 600;
  return s;
}

Scale quickScale() {
  Scale s = defaultScale();
  s.mode = "quick";
  s.buildings = {"l-shape", "z-building"};
  s.floorInComparisons = false;   // the floor only in Figs. 4 and 6
  s.gridResolutions = {8, 24, 64, 128};
  s.hgridMax = {32, 128, 512};
  s.photonsPerLight = 300;
  s.fewPhotonsPerLight = 120;
  s.uniformGrids = {{"l-shape", {8}}};
  s.renderWidth = 64, s.renderHeight = 48;
  s.timeoutSeconds = 180;
  return s;
}

// The ctest's: one small building for everything, a point or two per sweep.
Scale smokeScale() {
  Scale s = quickScale();
  s.mode = "smoke";
  s.buildings = {"l-shape"};
  s.floorBuilding = "l-shape";
  s.gridResolutions = {16, 48};
  s.hgridMax = {16, 128};
  s.hgridResolution = 32;
  s.photonsPerLight = 100;
  s.fewPhotonsPerLight = 40;
  s.uniformGrids = {{"l-shape", {4}}};
  s.renderWidth = 16, s.renderHeight = 12;
  s.renderGather = 2;
  s.timeoutSeconds = 120;
  return s;
}

std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ','))
    if (!item.empty()) items.push_back(item);
  return items;
}

Scale chooseScale(const BenchPaperOptions& options) {
  Scale s = options.smoke ? smokeScale() : options.quick ? quickScale() : defaultScale();
  if (options.photonsPerLight) s.photonsPerLight = options.photonsPerLight;
  if (options.photonsPerLight) s.fewPhotonsPerLight = std::max<uint64_t>(1, options.photonsPerLight * 2 / 5);
  if (options.timeoutSeconds > 0) s.timeoutSeconds = options.timeoutSeconds;
  if (!options.buildings.empty()) {
    // --buildings picks the buildings of every experiment; the tower, when
    // listed, is the floor of Figs. 4 and 6 and is compared like the others.
    const std::vector<std::string> chosen = splitList(options.buildings);
    for (const std::string& name : chosen)
      if (!findBuildingPreset(name, name == "tower" ? 1 : 0) || name == "demo")
        throw std::invalid_argument(fmt::format("--buildings: unknown building '{}' (l-shape, z-building, octagon, "
                                                "soda-hall, tower)", name));
    s.buildings.clear();
    for (const std::string& name : chosen)
      if (name != "tower") s.buildings.push_back(name);
    const bool tower = std::find(chosen.begin(), chosen.end(), "tower") != chosen.end();
    s.floorBuilding = tower ? "tower" : chosen.front();
    s.floorInComparisons = tower;
    std::map<std::string, std::vector<uint32_t>> uniform;
    for (const auto& [name, grids] : s.uniformGrids)
      if (std::find(chosen.begin(), chosen.end(), name) != chosen.end()) uniform[name] = grids;
    s.uniformGrids = uniform;
  }
  return s;
}

// The buildings of the comparisons (Figs. 7-9, auto_vs_fixed): the mode's
// buildings, plus the floor where it is compared too.
std::vector<std::string> comparedBuildings(const Scale& scale) {
  std::vector<std::string> names = scale.buildings;
  if (scale.floorInComparisons && std::find(names.begin(), names.end(), scale.floorBuilding) == names.end())
    names.push_back(scale.floorBuilding);
  return names;
}

// ---------------------------------------------------------------------------
// Output helpers: tables on stdout, CSV files.

std::string formatSeconds(double seconds) { return std::isfinite(seconds) ? fmt::format("{:.2f}", seconds) : "n/a"; }
std::string formatRatio(double ratio) { return std::isfinite(ratio) ? fmt::format("{:.2f}", ratio) : "n/a"; }

void printTable(const std::string& title, const std::vector<std::string>& header,
                const std::vector<std::vector<std::string>>& rows, const std::string& footnote = "") {
  std::vector<size_t> widths(header.size());
  for (size_t c = 0; c < header.size(); ++c) widths[c] = header[c].size();
  for (const auto& row : rows)
    for (size_t c = 0; c < row.size() && c < widths.size(); ++c) widths[c] = std::max(widths[c], row[c].size());
  const auto line = [&](const std::vector<std::string>& cells) {
    std::string text;
    for (size_t c = 0; c < cells.size() && c < widths.size(); ++c)
      text += c == 0 ? fmt::format("{:<{}}", cells[c], widths[c]) : fmt::format("  {:>{}}", cells[c], widths[c]);
    return text + "\n";
  };
  std::cout << "\n== " << title << " ==\n" << line(header);
  for (const auto& row : rows) std::cout << line(row);
  if (!footnote.empty()) std::cout << footnote << "\n";
  std::cout.flush();
}

class Csv {
 public:
  explicit Csv(std::vector<std::string> header) : text_(join(header)) {}
  void row(const std::vector<std::string>& cells) { text_ += join(cells); }
  void write(const fs::path& path) const {
    std::ofstream out(path);
    out << text_;
    if (!out) throw std::runtime_error("cannot write " + path.string());
  }

 private:
  static std::string join(const std::vector<std::string>& cells) {
    std::string line;
    for (size_t i = 0; i < cells.size(); ++i) line += (i ? "," : "") + csvField(cells[i]);
    return line + "\n";
  }
  std::string text_;
};

// Colours of the structures, the same in every plot.
Rgb structureColor(const std::string& spec) {
  if (spec.rfind("grid", 0) == 0) return {31, 119, 180};
  if (spec.rfind("hgrid", 0) == 0) return {255, 127, 14};
  if (spec == "kd:median") return {44, 160, 44};
  if (spec == "kd:sah") return {214, 39, 40};
  if (spec == "kd:bbox") return {148, 103, 189};
  if (spec.rfind("kd", 0) == 0) return {140, 86, 75};
  if (spec == "embree") return {110, 110, 110};
  if (spec == "auto") return {227, 119, 194};
  if (spec.rfind("bvh", 0) == 0) return {188, 189, 34};
  return {23, 190, 207};
}
constexpr Rgb kBestGridColor{158, 202, 225};   // grid at its best resolution, beside plain `grid`
constexpr Rgb kSeriesColors[] = {{31, 119, 180}, {255, 127, 14}, {44, 160, 44},  {214, 39, 40},
                                 {148, 103, 189}, {140, 86, 75}, {227, 119, 194}, {23, 190, 207}};

// ---------------------------------------------------------------------------
// Stores and measurements.

struct Store {
  std::string building;    // preset name
  uint32_t grid = 0;       // 0: topological cells; RG: uniform voxel cells
  std::string path;
  size_t cells = 0, nonEmptyCells = 0;
  uint64_t triangles = 0;
  size_t lights = 0;
  std::string label() const { return grid ? fmt::format("{} RG{}", building, grid) : building; }
};

// One measurement: every run of one (store, accel, photons, render) setting.
struct Measurement {
  enum class Status { Ok, Unavailable, Failed };
  Status status = Status::Ok;
  std::string note;                  // why not Ok: the child's message
  std::vector<PipelineRunStats> runs;
  std::vector<std::string> loads;    // 1-minute load average as each run started
  uint64_t photons = 0;

  bool ok() const { return status == Status::Ok && !runs.empty(); }
  // The run with the median photon phase (the lower middle one for an even count).
  const PipelineRunStats& typical() const {
    std::vector<size_t> order(runs.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(),
              [&](size_t a, size_t b) { return runs[a].photonSeconds < runs[b].photonSeconds; });
    return runs[order[(order.size() - 1) / 2]];
  }
  double seconds() const { return ok() ? medianOf(&PipelineRunStats::photonSeconds) : kNaN; }
  double buildSeconds() const { return ok() ? medianOf(&PipelineRunStats::buildSeconds) : kNaN; }
  double renderSeconds() const { return ok() ? medianOf(&PipelineRunStats::renderSeconds) : kNaN; }
  std::string statusText() const {
    return status == Status::Ok ? "ok" : status == Status::Unavailable ? "unavailable" : "failed";
  }

 private:
  double medianOf(double PipelineRunStats::*field) const {
    std::vector<double> values;
    for (const PipelineRunStats& run : runs) values.push_back(run.*field);
    return median(values);
  }
};

// What a render asks for beyond the photon pass.
struct RenderSetting {
  uint32_t spp = 1, gather = 0, width = 8, height = 8;   // the photon-pass-only token render
  bool operator<(const RenderSetting& o) const {
    return std::tie(spp, gather, width, height) < std::tie(o.spp, o.gather, o.width, o.height);
  }
};

// "accelerators" of the statistics ("kd:sah=12;grid=3"), empty when not reported.
std::string acceleratorsText(const std::map<std::string, int64_t>& accelerators) {
  std::vector<std::string> items;
  for (const auto& [spec, cells] : accelerators) items.push_back(fmt::format("{}={}", spec, cells));
  return fmt::format("{}", fmt::join(items, ";"));
}

// The CSV columns every pipeline measurement has, after the experiment's own.
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

std::vector<std::string> concat(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

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

// ---------------------------------------------------------------------------
// The bench: stores, the memo of measurements, the summary.

class Bench {
 public:
  Bench(const BenchPaperOptions& options, Scale scale) : options_(options), scale_(std::move(scale)) {
    out_ = fs::absolute(options.out);
    fs::create_directories(out_ / "stores");
  }

  const Scale& scale() const { return scale_; }
  const fs::path& out() const { return out_; }
  nlohmann::json& summary() { return summary_; }

  // The generated building (topological cells), generated on first use and
  // kept under OUT/stores for later runs.
  const Store& topological(const std::string& building) { return store(building, 0); }
  // The same building re-cut into RG^3 voxel cells (`scene import --grid RG`).
  const Store& uniform(const std::string& building, uint32_t grid) { return store(building, grid); }

  // Photons of a pass over `building`: photons per light x the generated
  // building's lights (the uniform stores get the same count).
  uint64_t photons(const std::string& building, uint64_t perLight) {
    return perLight * std::max<size_t>(1, topological(building).lights);
  }

  // The photon pass (and render) of `store` with `accel`, run once per
  // setting however many experiments ask for it.
  const Measurement& measure(const Store& store, const std::string& accel, uint64_t photons,
                             const RenderSetting& render = {}) {
    const auto key = std::make_tuple(store.path, accel, photons, render);
    if (auto it = memo_.find(key); it != memo_.end()) return it->second;
    Measurement& m = memo_[key];
    m.photons = photons;
    for (uint32_t run = 0; run < std::max<uint32_t>(1, options_.runs); ++run)
      if (!runOnce(store, accel, photons, render, m)) break;
    return m;
  }

  void writeSummary() const {
    std::ofstream out(out_ / "summary.json");
    out << summary_.dump(2) << "\n";
    if (!out) throw std::runtime_error("cannot write " + (out_ / "summary.json").string());
  }

 private:
  const Store& store(const std::string& building, uint32_t grid) {
    const auto key = std::make_pair(building, grid);
    if (auto it = stores_.find(key); it != stores_.end()) return it->second;
    Store s;
    s.building = building;
    s.grid = grid;
    s.path = (out_ / "stores" / (grid ? fmt::format("{}-grid{}", building, grid) : building)).string();
    if (!fs::exists(fs::path(s.path) / "scene.db")) grid ? importUniform(s) : generate(s);
    const SceneStore scene = SceneStore::open(s.path);
    s.cells = scene.cells().size();
    for (const CellInfo& cell : scene.cells()) s.nonEmptyCells += cell.triangleCount > 0;
    s.triangles = scene.totalTriangles();
    s.lights = scene.lights().size();
    return stores_[key] = s;
  }

  void generate(const Store& s) {
    const std::optional<BuildingPreset> preset = findBuildingPreset(s.building, s.building == "tower" ? 1 : 0);
    if (!preset) throw std::invalid_argument("unknown building " + s.building);
    std::cout << fmt::format("generating {} (seed {}) into {} ...\n", s.building, options_.sceneSeed, s.path);
    std::cout.flush();
    const GeneratedBuildingStats g = generateBuilding(*preset, options_.sceneSeed, s.path);
    std::cout << fmt::format("  {} triangles, {} cells, {} lights in {:.1f} s\n", g.triangles, g.cells, g.lights,
                             g.seconds);
  }

  void importUniform(const Store& s) {
    const std::string source = topological(s.building).path;
    std::cout << fmt::format("cutting {} into RG={} voxel cells (scene import --grid {}) into {} ...\n", s.building,
                             s.grid, s.grid, s.path);
    std::cout.flush();
    ImportOptions options;
    options.gridResolution = s.grid;
    importBuilding({source}, s.path, options);
  }

  // One run into m; false when the setting cannot run (no point repeating it).
  bool runOnce(const Store& store, const std::string& accel, uint64_t photons, const RenderSetting& render,
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

  const BenchPaperOptions& options_;
  Scale scale_;
  fs::path out_;
  TemporaryDirectory work_{"portico-bench-paper"};
  std::map<std::pair<std::string, uint32_t>, Store> stores_;
  std::map<std::tuple<std::string, std::string, uint64_t, RenderSetting>, Measurement> memo_;
  size_t runCount_ = 0;
  nlohmann::json summary_ = nlohmann::json::object();
};

// ---------------------------------------------------------------------------
// Shared sweeps: the best grid resolution and the kd heuristics of a
// building, asked for by several experiments.

struct SweepPoint {
  std::string spec;
  const Measurement* m = nullptr;
};

std::vector<SweepPoint> gridSweep(Bench& bench, const std::string& building) {
  std::vector<SweepPoint> points;
  const uint64_t photons = bench.photons(building, bench.scale().photonsPerLight);
  for (int r : bench.scale().gridResolutions) {
    const std::string spec = fmt::format("grid:res={}", r);
    points.push_back({spec, &bench.measure(bench.topological(building), spec, photons)});
  }
  return points;
}

// The fastest of points (nullptr when none ran).
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

double secondsOf(const SweepPoint* p) { return p ? p->m->seconds() : kNaN; }
std::string specOf(const SweepPoint* p) { return p ? p->spec : "n/a"; }

Bar timeBar(const std::string& spec, double seconds, const std::string& note = "") {
  Bar bar;
  bar.value = std::isfinite(seconds) ? seconds : kNaN;
  bar.color = structureColor(spec);
  bar.above = std::isfinite(seconds) ? fmt::format("{:.1f}", seconds) : "n/a";
  bar.aboveNote = note;
  return bar;
}

std::string scaleNote(const Bench& bench, uint64_t perLight) {
  return fmt::format("{} photons/light (paper {})", perLight,
                     perLight == bench.scale().fewPhotonsPerLight ? kPaperFewPhotonsPerLight : kPaperPhotonsPerLight);
}

// ---------------------------------------------------------------------------
// Figs. 4 and 5: total photon-pass time against the uniform grid's
// resolution, per building; Embree as a flat baseline.

void experimentGridResolution(Bench& bench) {
  const Scale& scale = bench.scale();
  std::vector<std::string> buildings{scale.floorBuilding};
  for (const std::string& b : scale.buildings)
    if (b != scale.floorBuilding) buildings.push_back(b);
  Csv csv(concat({"building", "triangles", "cells", "photons", "resolution", "accel", "best"}, kMeasurementColumns));
  std::vector<std::string> header{"building"};
  for (int r : scale.gridResolutions) header.push_back(fmt::format("R={}", r));
  for (const char* h : {"best R", "best s", "embree s"}) header.push_back(h);
  std::vector<std::vector<std::string>> rows;
  PlotPanel floorPanel{fmt::format("Fig. 4: {} (one floor), grid resolution", scale.floorBuilding),
                       "grid resolution (voxels along the longest axis)", "photon pass s (builds included)",
                       false, false, {}};
  PlotPanel othersPanel{"Fig. 5: grid resolution per building", "grid resolution", "photon pass s", false, false, {}};
  nlohmann::json best = nlohmann::json::object();
  for (size_t b = 0; b < buildings.size(); ++b) {
    const std::string& building = buildings[b];
    const Store& store = bench.topological(building);
    const uint64_t photons = bench.photons(building, scale.photonsPerLight);
    const std::vector<SweepPoint> points = gridSweep(bench, building);
    const SweepPoint* winner = fastest(points);
    const Measurement& embree = bench.measure(store, "embree", photons);
    std::vector<std::string> row{building};
    PlotSeries series{building, kSeriesColors[b % 8], false, {}, {}, -1};
    for (size_t i = 0; i < points.size(); ++i) {
      const int r = scale.gridResolutions[i];
      row.push_back(formatSeconds(points[i].m->seconds()));
      series.x.push_back(r), series.y.push_back(points[i].m->seconds());
      if (&points[i] == winner) series.marked = int(i);
      csv.row(concat({building, std::to_string(store.triangles), std::to_string(store.cells), std::to_string(photons),
                      std::to_string(r), points[i].spec, &points[i] == winner ? "1" : "0"},
                     measurementCells(*points[i].m)));
    }
    csv.row(concat({building, std::to_string(store.triangles), std::to_string(store.cells), std::to_string(photons),
                    "", "embree", "0"},
                   measurementCells(embree)));
    const int bestR = winner ? scale.gridResolutions[size_t(winner - points.data())] : 0;
    row.push_back(winner ? std::to_string(bestR) : "n/a");
    row.push_back(formatSeconds(secondsOf(winner)));
    row.push_back(formatSeconds(embree.seconds()));
    rows.push_back(row);
    PlotSeries flat{"embree (" + building + ")", kSeriesColors[b % 8], true, {}, {}, -1};
    flat.x = {double(scale.gridResolutions.front()), double(scale.gridResolutions.back())};
    flat.y = {embree.seconds(), embree.seconds()};
    PlotPanel& panel = b == 0 ? floorPanel : othersPanel;
    panel.series.push_back(series);
    panel.series.push_back(flat);
    best[building] = {{"resolution", bestR}, {"seconds", secondsOf(winner)}, {"embree_seconds", embree.seconds()},
                      {"photons", photons}};
  }
  printTable(fmt::format("Figs. 4-5: photon pass (s, builds included) vs grid resolution; {}",
                         scaleNote(bench, scale.photonsPerLight)),
             header, rows, "paper: best R ~48 for hand-furnished (l-shape, octagon), ~96 for regular (z-building, tower)");
  csv.write(bench.out() / "fig4_5_grid_resolution.csv");
  std::vector<PlotPanel> panels{floorPanel};
  if (!othersPanel.series.empty()) panels.push_back(othersPanel);
  writePlotPng((bench.out() / "fig4_5_grid_resolution.png").string(), panels, 760, 480);
  bench.summary()["fig4_5_grid_resolution"] = {{"best_resolution", best}};
}

// ---------------------------------------------------------------------------
// Fig. 6: hierarchical grid initialisation time against the most triangles a
// voxel may hold before it is subdivided, with a fixed top resolution.

void experimentHgridInit(Bench& bench) {
  const Scale& scale = bench.scale();
  const std::string& building = scale.floorBuilding;
  const Store& store = bench.topological(building);
  const uint64_t photons = bench.photons(building, scale.photonsPerLight);
  Csv csv(concat({"building", "photons", "top_resolution", "max", "accel"}, kMeasurementColumns));
  std::vector<std::vector<std::string>> rows;
  PlotSeries build{"initialisation (builds, all workers)", kSeriesColors[1], false, {}, {}, -1};
  PlotSeries total{"photon pass (builds included)", kSeriesColors[0], true, {}, {}, -1};
  nlohmann::json points = nlohmann::json::array();
  for (int maxRefs : scale.hgridMax) {
    const std::string spec = fmt::format("hgrid:res={},max={}", scale.hgridResolution, maxRefs);
    const Measurement& m = bench.measure(store, spec, photons);
    rows.push_back({std::to_string(maxRefs), formatSeconds(m.buildSeconds()), formatSeconds(m.seconds())});
    build.x.push_back(maxRefs), build.y.push_back(m.buildSeconds());
    total.x.push_back(maxRefs), total.y.push_back(m.seconds());
    csv.row(concat({building, std::to_string(photons), std::to_string(scale.hgridResolution), std::to_string(maxRefs),
                    spec},
                   measurementCells(m)));
    points.push_back({{"max", maxRefs}, {"build_seconds", m.buildSeconds()}, {"seconds", m.seconds()}});
  }
  printTable(fmt::format("Fig. 6: hgrid:res={} on {}: initialisation vs max triangles per voxel; {}",
                         scale.hgridResolution, building, scaleNote(bench, scale.photonsPerLight)),
             {"max", "init s", "photon pass s"}, rows,
             "init s: the workers' accelerator builds added up (time_ms.accelerator_build); paper: init time falls "
             "as max grows");
  csv.write(bench.out() / "fig6_hgrid_init.csv");
  PlotPanel panel{fmt::format("Fig. 6: {}, hgrid top res {}", building, scale.hgridResolution),
                  "max triangles per voxel", "seconds", true, false, {build, total}};
  writePlotPng((bench.out() / "fig6_hgrid_init.png").string(), {panel}, 760, 480);
  // Does initialisation get cheaper as voxels may hold more (the paper's claim)?
  bool falls = true;
  for (size_t i = 1; i < build.y.size(); ++i) falls = falls && !(build.y[i] > build.y[i - 1] * 1.1);
  bench.summary()["fig6_hgrid_init"] = {{"building", building}, {"top_resolution", scale.hgridResolution},
                                        {"points", points}, {"init_falls_as_max_grows", falls}};
}

// ---------------------------------------------------------------------------
// Table 3: average kd-tree depth per heuristic. Depth is a property of the
// structure, not of the pipeline, so the cells are loaded and the trees
// built here, one cell at a time. A cell's depth is AcceleratorStats::
// averageDepth (over its non-empty leaves); the building's is the plain mean
// over its cells with triangles (each cell counts once, as the paper's
// "average depth obtained in cells"), and, in the CSV, the mean weighted by
// the cells' triangles.

struct DepthResult {
  double cellMean = 0, triangleWeighted = 0, buildSeconds = 0;
  uint32_t maxDepth = 0;
  size_t cells = 0;
};

std::map<std::string, DepthResult> kdDepths(const Store& store) {
  const SceneStore scene = SceneStore::open(store.path);
  std::map<std::string, DepthResult> results;
  std::map<std::string, double> weighted;
  uint64_t triangles = 0;
  for (const CellInfo& cell : scene.cells()) {
    if (cell.triangleCount == 0) continue;
    const auto geometry = CellGeometry::load(scene.cellPath(cell.id), cell.id, scene.materials().size());
    triangles += cell.triangleCount;
    for (const std::string& spec : kKdHeuristics) {
      const auto accelerator = buildAccelerator(parseAcceleratorSpec(spec), geometry->mesh());
      const AcceleratorStats& stats = accelerator->stats();
      DepthResult& r = results[spec];
      r.cellMean += stats.averageDepth;
      weighted[spec] += stats.averageDepth * double(cell.triangleCount);
      r.buildSeconds += stats.buildMs / 1e3;
      r.maxDepth = std::max(r.maxDepth, stats.maxDepth);
      ++r.cells;
    }
  }
  for (auto& [spec, r] : results) {
    r.cellMean /= double(std::max<size_t>(1, r.cells));
    r.triangleWeighted = weighted[spec] / double(std::max<uint64_t>(1, triangles));
  }
  return results;
}

void experimentKdDepth(Bench& bench) {
  const Scale& scale = bench.scale();
  const std::vector<std::string> buildings = comparedBuildings(scale);
  // The paper's Table 3, for comparison in the table.
  const std::map<std::string, std::array<double, 3>> paper{{"l-shape", {15.3, 26.04, 27.63}},
                                                           {"z-building", {15.18, 22.36, 32.73}},
                                                           {"octagon", {16.73, 26.33, 28.08}},
                                                           {"soda-hall", {16.2, 26.99, 27.80}},
                                                           {"tower", {15.88, 28.24, 40.26}}};
  Csv csv({"building", "cells", "heuristic", "depth_cell_mean", "depth_triangle_weighted", "max_depth",
           "build_s_one_thread", "paper_depth"});
  std::vector<std::vector<std::string>> rows;
  BarPanel panel{"Table 3: average kd-tree depth in cells", "average depth", {}, {}};
  for (const std::string& spec : kKdHeuristics) panel.legend.push_back({spec, structureColor(spec)});
  nlohmann::json summary = nlohmann::json::object();
  size_t orderingHolds = 0;
  for (const std::string& building : buildings) {
    const Store& store = bench.topological(building);
    std::cout << fmt::format("table 3: building the three kd-trees of {}'s {} cells ...\n", building, store.cells);
    std::cout.flush();
    const std::map<std::string, DepthResult> depths = kdDepths(store);
    std::vector<std::string> row{building};
    BarGroup group{building, "", {}};
    nlohmann::json entry = nlohmann::json::object();
    for (size_t h = 0; h < kKdHeuristics.size(); ++h) {
      const std::string& spec = kKdHeuristics[h];
      const DepthResult& r = depths.at(spec);
      const auto p = paper.find(building);
      row.push_back(fmt::format("{:.2f}", r.cellMean) +
                    (p != paper.end() ? fmt::format(" ({:.2f})", p->second[h]) : ""));
      Bar bar{r.cellMean, structureColor(spec), fmt::format("{:.1f}", r.cellMean), ""};
      group.bars.push_back(bar);
      csv.row({building, std::to_string(r.cells), spec, fmt::format("{:.3f}", r.cellMean),
               fmt::format("{:.3f}", r.triangleWeighted), std::to_string(r.maxDepth),
               fmt::format("{:.3f}", r.buildSeconds), p != paper.end() ? fmt::format("{}", p->second[h]) : ""});
      entry[spec] = {{"depth", r.cellMean}, {"depth_triangle_weighted", r.triangleWeighted},
                     {"build_seconds_one_thread", r.buildSeconds}};
    }
    const double median = depths.at("kd:median").cellMean, sah = depths.at("kd:sah").cellMean,
                 bbox = depths.at("kd:bbox").cellMean;
    const bool holds = median < sah && sah < bbox;   // the paper's order in every building
    orderingHolds += holds;
    entry["ordering_median_lt_sah_lt_bbox"] = holds;
    row.push_back(holds ? "yes" : "no");
    rows.push_back(row);
    panel.groups.push_back(group);
    summary[building] = entry;
  }
  printTable("Table 3: average kd-tree depth in cells, mean over cells with triangles (paper's value)",
             {"building", "kd:median", "kd:sah", "kd:bbox", "median<sah<bbox"}, rows);
  csv.write(bench.out() / "table3_kd_depth.csv");
  writeBarPlotPng((bench.out() / "table3_kd_depth.png").string(), {panel}, 200 + 140 * int(buildings.size()), 480);
  bench.summary()["table3_kd_depth"] = {{"depth", summary},
                                        {"paper_ordering_holds_in", orderingHolds},
                                        {"buildings", buildings.size()}};
}

// ---------------------------------------------------------------------------
// Figs. 7 and 8: the three kd heuristics at few and many photons per light
// (the paper's 20K and 50K, scaled): does the median win with few photons
// (cheap builds) and the SAH with many (fast traversal)?

void experimentKdHeuristics(Bench& bench) {
  const Scale& scale = bench.scale();
  const std::vector<std::string> buildings = comparedBuildings(scale);
  Csv csv(concat({"building", "photons_per_light", "photons", "accel", "winner"}, kMeasurementColumns));
  std::vector<std::vector<std::string>> rows;
  std::vector<BarPanel> panels;
  nlohmann::json winners = nlohmann::json::object();
  for (uint64_t perLight : {scale.fewPhotonsPerLight, scale.photonsPerLight}) {
    BarPanel panel{scaleNote(bench, perLight), "photon pass s", {}, {}};
    for (const std::string& spec : kKdHeuristics) panel.legend.push_back({spec, structureColor(spec)});
    panel.legend.push_back({"embree", structureColor("embree")});
    for (const std::string& building : buildings) {
      const Store& store = bench.topological(building);
      const uint64_t photons = bench.photons(building, perLight);
      const std::vector<SweepPoint> points = kdSweep(bench, store, photons);
      const SweepPoint* winner = fastest(points);
      const Measurement& embree = bench.measure(store, "embree", photons);
      std::vector<std::string> row{building, std::to_string(perLight), std::to_string(photons)};
      BarGroup group{building, "", {}};
      for (const SweepPoint& p : points) {
        row.push_back(formatSeconds(p.m->seconds()));
        group.bars.push_back(timeBar(p.spec, p.m->seconds()));
        csv.row(concat({building, std::to_string(perLight), std::to_string(photons), p.spec, &p == winner ? "1" : "0"},
                       measurementCells(*p.m)));
      }
      csv.row(concat({building, std::to_string(perLight), std::to_string(photons), "embree", "0"},
                     measurementCells(embree)));
      row.push_back(formatSeconds(embree.seconds()));
      row.push_back(specOf(winner));
      group.bars.push_back(timeBar("embree", embree.seconds()));
      rows.push_back(row);
      panel.groups.push_back(group);
      winners[building][perLight == scale.photonsPerLight ? "many" : "few"] = specOf(winner);
    }
    panels.push_back(panel);
  }
  printTable("Figs. 7-8: photon pass (s) per kd heuristic, few and many photons per light",
             {"building", "photons/light", "photons", "kd:median", "kd:sah", "kd:bbox", "embree", "best kd"}, rows,
             fmt::format("photons/light {} and {} stand for the paper's 20K and 50K; paper: median wins with few "
                         "photons (cheap builds), sah with many",
                         scale.fewPhotonsPerLight, scale.photonsPerLight));
  csv.write(bench.out() / "fig7_8_kd_heuristics.csv");
  writeBarPlotPng((bench.out() / "fig7_8_kd_heuristics.png").string(), panels,
                  260 + 150 * int(buildings.size()), 480);
  size_t medianFew = 0, sahMany = 0;
  for (const std::string& b : buildings) {
    medianFew += winners[b]["few"] == "kd:median";
    sahMany += winners[b]["many"] == "kd:sah";
  }
  bench.summary()["fig7_8_kd_heuristics"] = {{"winner", winners},
                                             {"photons_per_light_few", scale.fewPhotonsPerLight},
                                             {"photons_per_light_many", scale.photonsPerLight},
                                             {"median_wins_few_in", medianFew},
                                             {"sah_wins_many_in", sahMany},
                                             {"buildings", buildings.size()}};
}

// ---------------------------------------------------------------------------
// Fig. 9: the best of each structure with topological cells: the grid at
// its best resolution (Figs. 4-5), hgrid (defaults), the best kd heuristic
// (Fig. 8, many photons) and Embree.

struct BestOfStructures {
  std::vector<std::pair<std::string, SweepPoint>> entries;   // structure -> its best (spec, measurement)
  std::optional<std::pair<std::string, SweepPoint>> winner;    // among portico's own (Embree apart)
};

// The fastest of portico's own structures: Embree is the baseline beside them.
void chooseWinner(BestOfStructures& best) {
  for (const auto& entry : best.entries)
    if (entry.first != "embree" && entry.second.m->ok() &&
        (!best.winner || entry.second.m->seconds() < best.winner->second.m->seconds()))
      best.winner = entry;
}

BestOfStructures bestTopological(Bench& bench, const std::string& building) {
  const Store& store = bench.topological(building);
  const uint64_t photons = bench.photons(building, bench.scale().photonsPerLight);
  BestOfStructures best;
  const auto add = [&](const std::string& structure, const SweepPoint* p) {
    if (p) best.entries.push_back({structure, *p});
  };
  const std::vector<SweepPoint> grids = gridSweep(bench, building);
  const std::vector<SweepPoint> kds = kdSweep(bench, store, photons);
  const SweepPoint hgrid{"hgrid", &bench.measure(store, "hgrid", photons)};
  const SweepPoint embree{"embree", &bench.measure(store, "embree", photons)};
  add("grid", fastest(grids));
  add("hgrid", &hgrid);
  add("kd", fastest(kds));
  add("embree", &embree);
  chooseWinner(best);
  return best;
}

double entrySeconds(const BestOfStructures& best, const std::string& structure) {
  for (const auto& [name, point] : best.entries)
    if (name == structure) return point.m->seconds();
  return kNaN;
}

std::string entrySpec(const BestOfStructures& best, const std::string& structure) {
  for (const auto& [name, point] : best.entries)
    if (name == structure) return point.spec;
  return "n/a";
}

void experimentBestTopological(Bench& bench) {
  const Scale& scale = bench.scale();
  const std::vector<std::string> buildings = comparedBuildings(scale);
  const std::vector<std::string> structures{"grid", "hgrid", "kd", "embree"};
  Csv csv(concat({"building", "photons", "structure", "accel", "winner"}, kMeasurementColumns));
  std::vector<std::vector<std::string>> rows;
  BarPanel panel{fmt::format("Fig. 9: best per structure, topological cells, {}",
                             scaleNote(bench, scale.photonsPerLight)),
                 "photon pass s", {}, {}};
  for (const std::string& s : structures) panel.legend.push_back({s == "kd" ? "kd (best)" : s, structureColor(s)});
  nlohmann::json summary = nlohmann::json::object();
  size_t gridWins = 0;
  for (const std::string& building : buildings) {
    const BestOfStructures best = bestTopological(bench, building);
    const uint64_t photons = bench.photons(building, scale.photonsPerLight);
    std::vector<std::string> row{building};
    BarGroup group{building, "", {}};
    for (const std::string& structure : structures) {
      row.push_back(fmt::format("{} {}", formatSeconds(entrySeconds(best, structure)), entrySpec(best, structure)));
      group.bars.push_back(timeBar(structure == "kd" ? "kd" : structure, entrySeconds(best, structure)));
    }
    for (const auto& [structure, point] : best.entries)
      csv.row(concat({building, std::to_string(photons), structure, point.spec,
                      best.winner && best.winner->second.spec == point.spec ? "1" : "0"},
                     measurementCells(*point.m)));
    const std::string winner = best.winner ? best.winner->second.spec : "n/a";
    gridWins += best.winner && best.winner->first == "grid";
    const double bestSeconds = best.winner ? best.winner->second.m->seconds() : kNaN;
    row.push_back(winner);
    row.push_back(formatRatio(entrySeconds(best, "embree") / bestSeconds));
    rows.push_back(row);
    panel.groups.push_back(group);
    summary[building] = {{"winner", winner},
                         {"seconds", bestSeconds},
                         {"grid", entrySeconds(best, "grid")},
                         {"grid_spec", entrySpec(best, "grid")},
                         {"hgrid", entrySeconds(best, "hgrid")},
                         {"kd", entrySeconds(best, "kd")},
                         {"kd_spec", entrySpec(best, "kd")},
                         {"embree", entrySeconds(best, "embree")},
                         {"embree_over_best_portico", entrySeconds(best, "embree") / bestSeconds}};
  }
  printTable("Fig. 9: best photon pass (s) per structure, topological cells",
             {"building", "grid (best R)", "hgrid", "kd (best)", "embree", "winner (portico's)", "embree/winner"}, rows,
             "paper: with topological cells a regular grid is always fastest overall");
  csv.write(bench.out() / "fig9_best_topological.csv");
  writeBarPlotPng((bench.out() / "fig9_best_topological.png").string(), {panel}, 260 + 150 * int(buildings.size()),
                  480);
  bench.summary()["fig9_best_topological"] = {
      {"per_building", summary}, {"grid_wins_in", gridWins}, {"buildings", buildings.size()}};
}

// ---------------------------------------------------------------------------
// Table 4: uniform (voxel) cells: the building re-cut into RG^3 cells, the
// best time per structure (grid: automatic or 16 voxels along the longest
// axis; hgrid defaults; kd: best heuristic; Embree).

struct UniformResult {
  const Store* store = nullptr;
  BestOfStructures best;
  std::vector<SweepPoint> kds;
};

UniformResult bestUniform(Bench& bench, const std::string& building, uint32_t grid) {
  UniformResult result;
  const Store& store = bench.uniform(building, grid);
  result.store = &store;
  const uint64_t photons = bench.photons(building, bench.scale().photonsPerLight);
  std::vector<SweepPoint> grids;
  for (const char* spec : {"grid", "grid:res=16"}) grids.push_back({spec, &bench.measure(store, spec, photons)});
  result.kds = kdSweep(bench, store, photons);
  const SweepPoint hgrid{"hgrid", &bench.measure(store, "hgrid", photons)};
  const SweepPoint embree{"embree", &bench.measure(store, "embree", photons)};
  BestOfStructures& best = result.best;
  if (const SweepPoint* p = fastest(grids)) best.entries.push_back({"grid", *p});
  best.entries.push_back({"hgrid", hgrid});
  if (const SweepPoint* p = fastest(result.kds)) best.entries.push_back({"kd", *p});
  best.entries.push_back({"embree", embree});
  chooseWinner(best);
  return result;
}

void experimentUniformCells(Bench& bench) {
  const Scale& scale = bench.scale();
  const std::map<std::string, std::string> paper{{"l-shape", "RG 10 / 300 cells, 1159 tri: grid 113, hgrid 210, kd 46"},
                                                 {"octagon", "RG 16 / 768, 7206 tri: 935, 1101, 593"},
                                                 {"soda-hall", "RG 16 / 1760, 978 tri: 1575, 2760, 928"}};
  Csv csv(concat({"building", "rg", "cells", "non_empty_cells", "avg_triangles_per_cell", "avg_triangles_per_non_empty",
                  "photons", "structure", "accel", "winner"},
                 kMeasurementColumns));
  std::vector<std::vector<std::string>> rows;
  BarPanel panel{fmt::format("Table 4: uniform cells, {}", scaleNote(bench, scale.photonsPerLight)),
                 "photon pass s", {}, {}};
  for (const std::string s : {"grid", "hgrid", "kd", "embree"})
    panel.legend.push_back({s == "kd" ? "kd (best)" : s, structureColor(s)});
  nlohmann::json summary = nlohmann::json::object();
  for (const auto& [building, grids] : scale.uniformGrids) {
    for (uint32_t rg : grids) {
      const UniformResult r = bestUniform(bench, building, rg);
      const Store& store = *r.store;
      const uint64_t photons = bench.photons(building, scale.photonsPerLight);
      const double avg = double(store.triangles) / double(std::max<size_t>(1, store.cells));
      const double avgNonEmpty = double(store.triangles) / double(std::max<size_t>(1, store.nonEmptyCells));
      const std::vector<std::string> storeCells{building,
                                                std::to_string(rg),
                                                std::to_string(store.cells),
                                                std::to_string(store.nonEmptyCells),
                                                fmt::format("{:.1f}", avg),
                                                fmt::format("{:.1f}", avgNonEmpty),
                                                std::to_string(photons)};
      std::vector<const SweepPoint*> all;
      for (const auto& entry : r.best.entries) all.push_back(&entry.second);
      for (const SweepPoint& p : r.kds) all.push_back(&p);
      std::set<std::string> written;
      for (const auto& [structure, point] : r.best.entries) {
        written.insert(point.spec);
        csv.row(concat(concat(storeCells, {structure, point.spec,
                                           r.best.winner && r.best.winner->second.spec == point.spec ? "1" : "0"}),
                       measurementCells(*point.m)));
      }
      for (const SweepPoint& p : r.kds)   // the other heuristics too: which suits voxel cells (paper: bbox)
        if (!written.count(p.spec))
          csv.row(concat(concat(storeCells, {"kd", p.spec, "0"}), measurementCells(*p.m)));
      const std::string winner = r.best.winner ? r.best.winner->second.spec : "n/a";
      rows.push_back({building, std::to_string(rg),
                      fmt::format("{} ({} non-empty)", store.cells, store.nonEmptyCells), fmt::format("{:.0f}", avg),
                      fmt::format("{} {}", formatSeconds(entrySeconds(r.best, "grid")), entrySpec(r.best, "grid")),
                      formatSeconds(entrySeconds(r.best, "hgrid")),
                      fmt::format("{} {}", formatSeconds(entrySeconds(r.best, "kd")), entrySpec(r.best, "kd")),
                      formatSeconds(entrySeconds(r.best, "embree")), winner});
      BarGroup group{fmt::format("{} RG{}", building, rg), fmt::format("{} cells", store.cells), {}};
      for (const std::string s : {"grid", "hgrid", "kd", "embree"})
        group.bars.push_back(timeBar(s, entrySeconds(r.best, s)));
      panel.groups.push_back(group);
      summary[fmt::format("{} RG{}", building, rg)] = {
          {"building", building},       {"rg", rg},
          {"cells", store.cells},       {"non_empty_cells", store.nonEmptyCells},
          {"avg_triangles_per_cell", avg}, {"winner", winner},
          {"seconds", r.best.winner ? r.best.winner->second.m->seconds() : kNaN},
          {"grid", entrySeconds(r.best, "grid")}, {"hgrid", entrySeconds(r.best, "hgrid")},
          {"kd", entrySeconds(r.best, "kd")},   {"kd_spec", entrySpec(r.best, "kd")},
          {"embree", entrySeconds(r.best, "embree")}};
    }
  }
  std::string paperNote = "paper (s, 2006): ";
  for (const auto& [building, text] : paper)
    if (scale.uniformGrids.count(building)) paperNote += building + " " + text + "; ";
  printTable("Table 4: uniform cells: best photon pass (s) per structure",
             {"building", "RG", "cells", "avg tri/cell", "grid", "hgrid", "kd (best)", "embree", "winner"}, rows,
             paperNote + "paper: kd (bbox) fastest with uniform cells");
  csv.write(bench.out() / "table4_uniform_cells.csv");
  writeBarPlotPng((bench.out() / "table4_uniform_cells.png").string(), {panel},
                  260 + 150 * std::max<int>(1, int(panel.groups.size())), 480);
  bench.summary()["table4_uniform_cells"] = summary;
}

// ---------------------------------------------------------------------------
// Fig. 11: the best photon pass with topological cells against the best with
// uniform cells, and a real render (camera rays, final gathering) of both:
// its time and the share of its rays that cross a portal.

void experimentTopologicalVsUniform(Bench& bench) {
  const Scale& scale = bench.scale();
  Csv csv(concat({"building", "cells_kind", "rg", "cells", "photons", "kind", "accel"}, kMeasurementColumns));
  std::vector<std::vector<std::string>> rows;
  BarPanel photonPanel{"Fig. 11: best photon pass, topological vs uniform cells", "photon pass s", {}, {}};
  BarPanel renderPanel{fmt::format("render {}x{}, 1 spp, gather {}, {}", scale.renderWidth, scale.renderHeight,
                                   scale.renderGather, scale.renderAccel),
                       "render s", {}, {}};
  const Rgb topoColor{31, 119, 180}, uniformColor{255, 127, 14};
  for (BarPanel* p : {&photonPanel, &renderPanel})
    p->legend = {{"topological", topoColor}, {"uniform", uniformColor}};
  nlohmann::json summary = nlohmann::json::object();
  for (const auto& [building, grids] : scale.uniformGrids) {
    const BestOfStructures topo = bestTopological(bench, building);
    // The uniform cut with the fastest photon pass.
    std::optional<UniformResult> uniformBest;
    for (uint32_t rg : grids) {
      UniformResult r = bestUniform(bench, building, rg);
      if (r.best.winner && (!uniformBest || !uniformBest->best.winner ||
                            r.best.winner->second.m->seconds() < uniformBest->best.winner->second.m->seconds()))
        uniformBest = std::move(r);
    }
    if (!uniformBest) continue;
    const double topoSeconds = topo.winner ? topo.winner->second.m->seconds() : kNaN;
    const double uniformSeconds = uniformBest->best.winner ? uniformBest->best.winner->second.m->seconds() : kNaN;
    // The render: same photons per light, camera rays with final gathering.
    const RenderSetting render{1, scale.renderGather, scale.renderWidth, scale.renderHeight};
    const uint64_t photons = bench.photons(building, scale.fewPhotonsPerLight);
    const Store& topoStore = bench.topological(building);
    const Store& uniformStore = *uniformBest->store;
    const Measurement& topoRender = bench.measure(topoStore, scale.renderAccel, photons, render);
    const Measurement& uniformRender = bench.measure(uniformStore, scale.renderAccel, photons, render);
    const auto portalShare = [](const Measurement& m) {
      if (!m.ok()) return kNaN;
      const PipelineRunStats& s = m.typical();
      const int64_t started = s.cameraRays + s.shadowRays + s.gatherRays;
      return started > 0 ? double(s.rayCrossings) / double(started) : kNaN;
    };
    const auto tracedShare = [](const Measurement& m) {
      return m.ok() && m.typical().raysTraced > 0 ? double(m.typical().rayCrossings) / double(m.typical().raysTraced)
                                                  : kNaN;
    };
    const double renderRatio = uniformRender.renderSeconds() / topoRender.renderSeconds();
    rows.push_back({building, formatSeconds(topoSeconds) + " " + (topo.winner ? topo.winner->second.spec : ""),
                    fmt::format("{} {} RG{}", formatSeconds(uniformSeconds),
                                uniformBest->best.winner ? uniformBest->best.winner->second.spec : "",
                                uniformStore.grid),
                    formatRatio(uniformSeconds / topoSeconds), formatSeconds(topoRender.renderSeconds()),
                    formatSeconds(uniformRender.renderSeconds()), formatRatio(renderRatio),
                    fmt::format("{:.3f}", portalShare(topoRender)), fmt::format("{:.3f}", portalShare(uniformRender))});
    const auto csvRow = [&](const Store& store, const char* kind, const std::string& accel, const Measurement& m) {
      csv.row(concat({building, store.grid ? "uniform" : "topological", std::to_string(store.grid),
                      std::to_string(store.cells), std::to_string(m.photons), kind, accel},
                     measurementCells(m)));
    };
    if (topo.winner) csvRow(topoStore, "photon_pass_best", topo.winner->second.spec, *topo.winner->second.m);
    if (uniformBest->best.winner)
      csvRow(uniformStore, "photon_pass_best", uniformBest->best.winner->second.spec,
             *uniformBest->best.winner->second.m);
    csvRow(topoStore, "render", scale.renderAccel, topoRender);
    csvRow(uniformStore, "render", scale.renderAccel, uniformRender);
    photonPanel.groups.push_back({building, fmt::format("x{:.2f}", uniformSeconds / topoSeconds),
                                  {Bar{topoSeconds, topoColor, formatSeconds(topoSeconds), ""},
                                   Bar{uniformSeconds, uniformColor, formatSeconds(uniformSeconds), ""}}});
    renderPanel.groups.push_back(
        {building, fmt::format("x{:.2f}", renderRatio),
         {Bar{topoRender.renderSeconds(), topoColor, formatSeconds(topoRender.renderSeconds()),
              fmt::format("{:.3f}/ray", portalShare(topoRender))},
          Bar{uniformRender.renderSeconds(), uniformColor, formatSeconds(uniformRender.renderSeconds()),
              fmt::format("{:.3f}/ray", portalShare(uniformRender))}}});
    summary[building] = {{"photon_pass_topological", topoSeconds},
                         {"photon_pass_uniform", uniformSeconds},
                         {"uniform_rg", uniformStore.grid},
                         {"photon_pass_ratio_uniform_over_topological", uniformSeconds / topoSeconds},
                         {"render_topological", topoRender.renderSeconds()},
                         {"render_uniform", uniformRender.renderSeconds()},
                         {"render_ratio_uniform_over_topological", renderRatio},
                         {"portal_crossings_per_render_ray_topological", portalShare(topoRender)},
                         {"portal_crossings_per_render_ray_uniform", portalShare(uniformRender)},
                         {"ray_crossings_over_rays_traced_topological", tracedShare(topoRender)},
                         {"ray_crossings_over_rays_traced_uniform", tracedShare(uniformRender)}};
  }
  printTable("Fig. 11: topological vs uniform cells: best photon pass (s) and a render (s)",
             {"building", "topological best", "uniform best", "uni/topo", "render topo", "render uni", "uni/topo",
              "crossings/ray topo", "crossings/ray uni"},
             rows,
             fmt::format("render: {}x{}, 1 spp, final gather {} rays, --accel {}, {} photons/light; crossings/ray: "
                         "portal crossings of render rays per render ray started (camera + shadow + gather). paper: "
                         "rendering >= 4x faster with topological cells, < 5 % of rays hit portals",
                         scale.renderWidth, scale.renderHeight, scale.renderGather, scale.renderAccel,
                         scale.fewPhotonsPerLight));
  csv.write(bench.out() / "fig11_topological_vs_uniform.csv");
  const int groups = std::max<int>(1, int(photonPanel.groups.size()));
  writeBarPlotPng((bench.out() / "fig11_topological_vs_uniform.png").string(), {photonPanel, renderPanel},
                  300 + 150 * groups, 480);
  bench.summary()["fig11_topological_vs_uniform"] = summary;
}

// ---------------------------------------------------------------------------
// auto_vs_fixed: `--accel auto` (a structure chosen per cell by the workers)
// beside every fixed choice. Until the pipeline knows `auto` its runs are
// refused; the experiment says so instead of failing.

void experimentAutoVsFixed(Bench& bench) {
  const Scale& scale = bench.scale();
  const std::vector<std::string> buildings = comparedBuildings(scale);
  Csv csv(concat({"building", "photons", "choice", "accel", "ratio_auto_over_this"}, kMeasurementColumns));
  std::vector<std::vector<std::string>> rows;
  BarPanel panel{fmt::format("--accel auto vs fixed choices, {}", scaleNote(bench, scale.photonsPerLight)),
                 "photon pass s", {}, {}};
  nlohmann::json summary = nlohmann::json::object();
  std::string autoStatus = "ok";
  for (const std::string& building : buildings) {
    const Store& store = bench.topological(building);
    const uint64_t photons = bench.photons(building, scale.photonsPerLight);
    const std::vector<SweepPoint> grids = gridSweep(bench, building);
    const SweepPoint* bestGrid = fastest(grids);
    std::vector<SweepPoint> fixed{{"grid", &bench.measure(store, "grid", photons)}};
    if (bestGrid) fixed.push_back(*bestGrid);
    fixed.push_back({"hgrid", &bench.measure(store, "hgrid", photons)});
    for (const SweepPoint& p : kdSweep(bench, store, photons)) fixed.push_back(p);
    fixed.push_back({"bvh", &bench.measure(store, "bvh", photons)});
    const SweepPoint* bestFixed = fastest(fixed);
    const Measurement& automatic = bench.measure(store, "auto", photons);
    const Measurement& embree = bench.measure(store, "embree", photons);
    if (!automatic.ok()) autoStatus = automatic.statusText();
    const double ratio = automatic.seconds() / secondsOf(bestFixed);
    BarGroup group{building, automatic.ok() ? fmt::format("auto/best x{:.2f}", ratio) : "auto " + automatic.statusText(),
                   {}};
    std::vector<std::string> row{building};
    for (const SweepPoint& p : fixed) {
      row.push_back(formatSeconds(p.m->seconds()));
      group.bars.push_back(timeBar(p.spec, p.m->seconds()));
      if (p.spec.rfind("grid:res=", 0) == 0) group.bars.back().color = kBestGridColor;   // apart from plain grid
      csv.row(concat({building, std::to_string(photons), &p == bestFixed ? "best_fixed" : "fixed", p.spec,
                      formatRatio(automatic.seconds() / p.m->seconds())},
                     measurementCells(*p.m)));
    }
    csv.row(concat({building, std::to_string(photons), "auto", "auto", "1"}, measurementCells(automatic)));
    csv.row(concat({building, std::to_string(photons), "baseline", "embree",
                    formatRatio(automatic.seconds() / embree.seconds())},
                   measurementCells(embree)));
    Bar autoBar = timeBar("auto", automatic.seconds());
    if (!automatic.ok()) autoBar.above = automatic.statusText() == "unavailable" ? "n/a" : "failed";
    group.bars.push_back(autoBar);
    group.bars.push_back(timeBar("embree", embree.seconds()));
    row.push_back(automatic.ok() ? formatSeconds(automatic.seconds()) : automatic.statusText());
    row.push_back(formatSeconds(embree.seconds()));
    row.push_back(specOf(bestFixed));
    row.push_back(formatRatio(ratio));
    row.push_back(acceleratorsText(automatic.ok() ? automatic.typical().accelerators : std::map<std::string, int64_t>{}));
    rows.push_back(row);
    panel.groups.push_back(group);
    summary[building] = {{"auto_status", automatic.statusText()},
                         {"auto_note", automatic.note},
                         {"auto_seconds", automatic.seconds()},
                         {"best_fixed", specOf(bestFixed)},
                         {"best_fixed_seconds", secondsOf(bestFixed)},
                         {"embree_seconds", embree.seconds()},
                         {"ratio_auto_over_best_fixed", ratio},
                         {"accelerators", automatic.ok() ? nlohmann::json(automatic.typical().accelerators)
                                                         : nlohmann::json::object()}};
  }
  for (const std::string s :
       {"grid", "grid:res=R (best)", "hgrid", "kd:median", "kd:sah", "kd:bbox", "bvh", "auto", "embree"})
    panel.legend.push_back({s, s == "grid:res=R (best)" ? kBestGridColor : structureColor(s)});
  printTable("auto_vs_fixed: photon pass (s) of --accel auto beside every fixed choice",
             {"building", "grid", "grid best R", "hgrid", "kd:median", "kd:sah", "kd:bbox", "bvh", "auto", "embree",
              "best fixed", "auto/best", "auto's choices"},
             rows,
             autoStatus == "ok" ? "auto's choices: the statistics' \"accelerators\" (spec=cells)"
                                : "auto is " + autoStatus + " in this build (the pipeline refused --accel auto)");
  csv.write(bench.out() / "auto_vs_fixed.csv");
  writeBarPlotPng((bench.out() / "auto_vs_fixed.png").string(), {panel}, 420 + 240 * int(buildings.size()), 480);
  bench.summary()["auto_vs_fixed"] = {{"auto_status", autoStatus}, {"per_building", summary}};
}

// ---------------------------------------------------------------------------

std::string scaleHeader(const BenchPaperOptions& options, const Scale& s) {
  std::string uniform;
  for (const auto& [building, grids] : s.uniformGrids)
    uniform += fmt::format("{}{} RG {}", uniform.empty() ? "" : "; ", building, fmt::join(grids, ","));
  return fmt::format(
      "portico bench paper ({} scale): Fradin & Meneveaux 2006, section 6, through the real pipeline\n"
      "  every time: time_ms.photons of one `portico render` child (coordinator + {} workers, --spp 1 --gather 0 "
      "--width 8 --height 8),\n"
      "  from submission to the last photon Result, cell loads and accelerator builds included; {} run(s) per "
      "measurement (median)\n"
      "  photons: {} per light (paper 50 000), few {} per light (paper 20 000), x the building's lights; seed {}, "
      "scene seed {}\n"
      "  buildings: {}; one floor: {} (Figs. 4, 6{}); grid R {}; hgrid res {} max {}\n"
      "  uniform cells: {}; render: {}x{} 1 spp gather {} --accel {}\n"
      "  machine: {} cores (hardware threads), worker memory {}, run timeout {:.0f} s\n",
      s.mode, options.workers, std::max<uint32_t>(1, options.runs), s.photonsPerLight, s.fewPhotonsPerLight,
      options.seed, options.sceneSeed, fmt::join(s.buildings, ", "), s.floorBuilding,
      s.floorInComparisons ? ", and compared in Figs. 7-9 and auto_vs_fixed" : "", fmt::join(s.gridResolutions, ","),
      s.hgridResolution, fmt::join(s.hgridMax, ","), uniform.empty() ? "none" : uniform, s.renderWidth, s.renderHeight,
      s.renderGather, s.renderAccel, std::thread::hardware_concurrency(), options.memory, s.timeoutSeconds);
}

nlohmann::json scaleJson(const BenchPaperOptions& options, const Scale& s) {
  return {{"mode", s.mode},
          {"workers", options.workers},
          {"runs", std::max<uint32_t>(1, options.runs)},
          {"photons_per_light", s.photonsPerLight},
          {"few_photons_per_light", s.fewPhotonsPerLight},
          {"paper_photons_per_light", kPaperPhotonsPerLight},
          {"paper_few_photons_per_light", kPaperFewPhotonsPerLight},
          {"buildings", s.buildings},
          {"floor_building", s.floorBuilding},
          {"grid_resolutions", s.gridResolutions},
          {"hgrid_resolution", s.hgridResolution},
          {"hgrid_max", s.hgridMax},
          {"uniform_grids", s.uniformGrids},
          {"render", {{"width", s.renderWidth}, {"height", s.renderHeight}, {"spp", 1},
                      {"gather", s.renderGather}, {"accel", s.renderAccel}}},
          {"seed", options.seed},
          {"scene_seed", options.sceneSeed},
          {"cores", std::thread::hardware_concurrency()}};
}

using Experiment = std::function<void(Bench&)>;

const std::map<std::string, Experiment>& experiments() {
  static const std::map<std::string, Experiment> table{
      {"fig4_5_grid_resolution", experimentGridResolution},
      {"fig6_hgrid_init", experimentHgridInit},
      {"table3_kd_depth", experimentKdDepth},
      {"fig7_8_kd_heuristics", experimentKdHeuristics},
      {"fig9_best_topological", experimentBestTopological},
      {"table4_uniform_cells", experimentUniformCells},
      {"fig11_topological_vs_uniform", experimentTopologicalVsUniform},
      {"auto_vs_fixed", experimentAutoVsFixed}};
  return table;
}

}  // namespace

int runBenchPaper(const BenchPaperOptions& options) {
  if (options.workers == 0) throw std::invalid_argument("--workers must be at least 1");
  const Scale scale = chooseScale(options);
  std::vector<std::string> chosen = options.experiments.empty() ? kExperiments : splitList(options.experiments);
  for (const std::string& name : chosen)
    if (!experiments().count(name))
      throw std::invalid_argument(
          fmt::format("--experiments: unknown '{}' (known: {})", name, fmt::join(kExperiments, ", ")));
  const auto start = Clock::now();
  Bench bench(options, scale);
  const std::string header = scaleHeader(options, scale);
  std::cout << header;
  std::cout.flush();
  {
    std::ofstream readme(bench.out() / "README.txt");
    readme << header;
  }
  bench.summary()["scale"] = scaleJson(options, scale);
  bench.summary()["paper"] = "Fradin & Meneveaux 2006, Acceleration schemes for ray tracing large buildings, section 6";
  for (const std::string& name : kExperiments) {   // the paper's order, whatever the order asked
    if (std::find(chosen.begin(), chosen.end(), name) == chosen.end()) continue;
    const auto experimentStart = Clock::now();
    experiments().at(name)(bench);
    bench.summary()["seconds"][name] = secondsSince(experimentStart);
    bench.writeSummary();   // after every experiment: an interrupted run keeps what it measured
    std::cout << fmt::format("wrote {}.csv and {}.png ({:.0f} s)\n", (bench.out() / name).string(), name,
                             secondsSince(experimentStart));
    std::cout.flush();
  }
  bench.summary()["seconds"]["total"] = secondsSince(start);
  bench.writeSummary();
  std::cout << fmt::format("\nportico bench paper: {} experiment(s) in {:.0f} s; wrote {}\n", chosen.size(),
                           secondsSince(start), (bench.out() / "summary.json").string());
  return 0;
}

}  // namespace portico::cli
