// `portico bench calibrate`: measures, on this machine, the build time and
// the per-ray tracing time of every candidate of `--accel auto` on cells of
// many sizes and shapes, fits the cost model's coefficients
// (common/accel/cost_model.h) and stores them where the workers look.
//
// The cells: every cell of a generated building (rooms, corridors, halls and
// facade strips as the renderer meets them: `--preset`, l-shape by default)
// and furnished halls of chosen sizes (dense open-plan cells up to hundreds
// of thousands of triangles, which small buildings lack). The rays: photon-
// like (from surfaces, cosine-distributed), the renderer's commonest kind.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "common/accel/cost_model.h"
#include "common/scene/generator/building_presets.h"
#include "common/scene/generator/building_generator.h"
#include "common/scene/store/cell_geometry.h"
#include "common/scene/store/scene_store.h"
#include "common/util/temporary_directory.h"
#include "coordinator/cli/bench/accel_measure.h"
#include "coordinator/cli/bench/bench_calibrate.h"
#include "common/util/csv_field.h"

namespace portico::cli {

namespace {

// One cell to measure on.
struct CalibrationCell {
  std::string name;
  MeshView mesh;
  CellShape shape;
};

struct Measurement {
  std::string cell;
  AcceleratorCandidate candidate;
  CellShape shape;
  double buildMs = 0;
  double traceNsPerRay = 0;
};

// Grid resolutions measured (the model interpolates between them).
const std::vector<int> kMeasuredGridResolutions{4, 8, 16, 32, 64, 128};

// The candidates measured on a cell: the model's own, with the grid
// resolutions thinned to kMeasuredGridResolutions (plain `grid`, at its own
// resolution, always measured).
std::vector<AcceleratorCandidate> measuredCandidates(const CostModel& model, const CellShape& shape) {
  std::vector<AcceleratorCandidate> list;
  for (const AcceleratorCandidate& c : model.candidates(shape))
    if (c.family != "grid" || c.gridResolution == 0 ||
        std::find(kMeasuredGridResolutions.begin(), kMeasuredGridResolutions.end(), c.gridResolution) !=
            kMeasuredGridResolutions.end())
      list.push_back(c);
  return list;
}

std::vector<Measurement> measureCell(const CostModel& model, const CalibrationCell& cell,
                                     const CalibrateOptions& options) {
  const std::vector<Ray> rays = photonRays(cell.mesh, options.rays, options.seed);
  std::vector<Measurement> measured;
  for (const AcceleratorCandidate& candidate : measuredCandidates(model, cell.shape)) {
    Measurement m;
    m.cell = cell.name;
    m.candidate = candidate;
    m.shape = cell.shape;
    // Small builds are noisy: take the median of a few.
    const uint32_t buildRuns = cell.shape.triangles < 20000 ? 3 : 1;
    const auto accelerator = timedBuild(parseAcceleratorSpec(candidate.spec), cell.mesh, buildRuns, m.buildMs);
    const TraceResult traced = traceRays(*accelerator, rays, options.runs);
    m.traceNsPerRay = traced.mraysPerSecond > 0 ? 1e3 / traced.mraysPerSecond : 0;
    measured.push_back(m);
  }
  return measured;
}

// Fits one family's build and trace coefficients to its measurements.
FamilyCoefficients fitFamily(const std::vector<Measurement>& all, const std::string& family) {
  std::vector<std::vector<double>> buildX, traceX;
  std::vector<double> buildY, traceY;
  for (const Measurement& m : all) {
    if (m.candidate.family != family) continue;
    buildX.push_back(buildFeatures(m.candidate, m.shape));
    buildY.push_back(std::max(1e-3, m.buildMs));
    traceX.push_back(traceFeatures(m.candidate, m.shape));
    traceY.push_back(std::max(1.0, m.traceNsPerRay));
  }
  if (buildX.empty()) throw std::runtime_error("calibration: no measurement of " + family);
  return {fitNonNegativeRelative(buildX, buildY), fitNonNegativeRelative(traceX, traceY)};
}

// Median of |predicted / measured - 1| over the family's measurements.
std::pair<double, double> fitErrors(const CostModel& model, const std::vector<Measurement>& all,
                                    const std::string& family) {
  std::vector<double> build, trace;
  for (const Measurement& m : all) {
    if (m.candidate.family != family) continue;
    const CostPrediction p = model.predict(m.candidate, m.shape);
    build.push_back(std::fabs(p.buildMs / std::max(1e-3, m.buildMs) - 1));
    trace.push_back(std::fabs(p.traceNsPerRay / std::max(1.0, m.traceNsPerRay) - 1));
  }
  return {median(build), median(trace)};
}

std::vector<std::unique_ptr<CellGeometry>> loadBuildingCells(const std::string& store, size_t maxCells) {
  const SceneStore scene = SceneStore::open(store);
  // Up to maxCells cells spread evenly over the sizes (smallest to largest).
  std::vector<uint32_t> order;
  for (const CellInfo& cell : scene.cells())
    if (cell.triangleCount >= 12) order.push_back(cell.id);
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    return scene.cells()[a].triangleCount < scene.cells()[b].triangleCount;
  });
  std::vector<std::unique_ptr<CellGeometry>> cells;
  const size_t take = std::min(order.size(), maxCells);
  for (size_t i = 0; i < take; ++i) {
    const uint32_t id = order[take > 1 ? i * (order.size() - 1) / (take - 1) : 0];
    cells.push_back(CellGeometry::load(scene.cellPath(id), id, scene.materials().size()));
  }
  return cells;
}

}  // namespace

int runBenchCalibrate(const CalibrateOptions& options) {
  const std::string output = options.output.empty() ? CostModel::defaultPath() : options.output;
  const CostModel starting = CostModel::builtIn();   // only its candidate list is used
  const auto started = Clock::now();

  // The building's cells.
  const TemporaryDirectory temporary("portico-calibrate");
  std::string store = options.store;
  if (store.empty()) {
    const std::optional<BuildingPreset> preset = findBuildingPreset(options.preset, 0);
    if (!preset) throw std::invalid_argument("--preset: unknown building preset '" + options.preset + "'");
    store = (temporary.path() / "building").string();
    generateBuilding(*preset, options.seed, store);
  }
  const auto buildingCells = loadBuildingCells(store, options.maxCells);
  std::vector<CalibrationCell> cells;
  for (const auto& geometry : buildingCells)
    cells.push_back({fmt::format("cell {}", geometry->id()), geometry->mesh(), cellShape(geometry->mesh())});

  // The halls.
  std::vector<FurnishedHall> halls;
  for (size_t size : parseTriangleCounts(options.sizes)) halls.push_back(generateFurnishedHall(size, options.seed));
  for (FurnishedHall& hall : halls) {
    const MeshView mesh = hallMesh(hall);
    cells.push_back({fmt::format("hall {}", mesh.triangleCount), mesh, cellShape(mesh)});
  }

  std::cout << fmt::format("calibrating the accelerator cost model on {} cells ({} of {}, {} halls), {} photon-like "
                           "rays each, one thread\n",
                           cells.size(), buildingCells.size(), options.store.empty() ? options.preset : store,
                           halls.size(), options.rays);
  std::vector<Measurement> measurements;
  for (const CalibrationCell& cell : cells) {
    const auto cellStart = Clock::now();
    auto measured = measureCell(starting, cell, options);
    std::cout << fmt::format("  {:<12} {:>8} triangles: {} structures in {:.1f} s\n", cell.name,
                             cell.mesh.triangleCount, measured.size(), secondsSince(cellStart));
    measurements.insert(measurements.end(), measured.begin(), measured.end());
  }

  CostModel model;
  model.origin = fmt::format("portico bench calibrate, {} cells, {} measurements", cells.size(), measurements.size());
  for (const auto& [family, unused] : starting.families) model.families[family] = fitFamily(measurements, family);

  std::cout << fmt::format("\n{:<10} {:>34} {:>9} {:>26} {:>9}\n", "family", "build ms ~ (1, n, n log n | voxels)",
                           "build err", "trace ns ~ (1, features)", "trace err");
  for (const auto& [family, c] : model.families) {
    const auto [buildError, traceError] = fitErrors(model, measurements, family);
    std::string build, trace;
    for (double v : c.build) build += fmt::format(" {:.3g}", v);
    for (double v : c.trace) trace += fmt::format(" {:.3g}", v);
    std::cout << fmt::format("{:<10} {:>34} {:>8.0f}% {:>26} {:>8.0f}%\n", family, build, 100 * buildError, trace,
                             100 * traceError);
  }
  if (!options.csv.empty()) {
    std::ofstream csv(options.csv);
    csv << "cell,spec,triangles,extent_x,extent_y,extent_z,build_ms,trace_ns_per_ray,predicted_build_ms,"
           "predicted_trace_ns_per_ray\n";
    for (const Measurement& m : measurements) {
      const CostPrediction p = model.predict(m.candidate, m.shape);
      csv << fmt::format("{},{},{},{:.3f},{:.3f},{:.3f},{:.4f},{:.1f},{:.4f},{:.1f}\n", m.cell, csvField(m.candidate.spec),
                         m.shape.triangles, m.shape.extent[0], m.shape.extent[1], m.shape.extent[2], m.buildMs,
                         m.traceNsPerRay, p.buildMs, p.traceNsPerRay);
    }
    if (!csv) throw std::runtime_error("cannot write " + options.csv);
  }
  model.save(output);
  std::cout << fmt::format("\nwrote {} in {:.0f} s; workers on this machine use it for --accel auto\n", output,
                           secondsSince(started));
  return 0;
}

}  // namespace portico::cli
