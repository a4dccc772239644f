#include "common/accel/cost_model.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "common/accel/uniform_grid.h"
#include "common/util/atomic_file.h"

namespace portico {

namespace {

constexpr int kCalibrationVersion = 1;

// A grid of more voxels than this many per triangle (plus a floor for tiny
// cells) is never worth its memory, whatever the model says.
constexpr double kMaxVoxelsPerTriangle = 64;
constexpr double kMinVoxelBudget = 4096;

const char* const kFamilies[] = {"grid", "hgrid", "kd:median", "kd:sah", "kd:bbox", "bvh"};
// Families a calibration written before they existed may lack: they take
// the built-in coefficients (and the model's origin says so).
const char* const kNewerFamilies[] = {"bvh"};

double log2Triangles(const CellShape& cell) { return std::log2(std::max(2.0, cell.triangles)); }

// Plain `grid` (gridResolution 0) takes the resolution the grid would pick
// itself; `grid:res=R` puts R voxels on the longest axis.
std::array<int, 3> gridResolution(const AcceleratorCandidate& candidate, const CellShape& cell) {
  if (candidate.gridResolution == 0)
    return automaticGridResolution(cell.extent, size_t(std::max(1.0, cell.triangles)), UniformGridOptions{}.density);
  return resolutionFromLongestAxis(cell.extent, candidate.gridResolution);
}

// Plain `grid` is chosen unless another candidate is predicted cheaper by
// more than this fraction. The model's trace error is of this order (14-23 %
// per family on a calibration's own cells), and it was fitted on cells
// measured one at a time and warm in cache: on soda-hall's office rooms it
// predicted grid:res=8 level with the grid's own resolution, which in the
// photon pass ran 14 % faster (docs/paper-results.md, §7). Scaling one
// candidate's whole cost keeps each choice the lower envelope of lines in
// the number of rays: more rays never buy a slower weighted trace.
constexpr double kPlainGridPreference = 0.10;

double dot(const std::vector<double>& a, const std::vector<double>& b) {
  double sum = 0;
  for (size_t i = 0; i < a.size() && i < b.size(); ++i) sum += a[i] * b[i];
  return sum;
}

// Solves the normal equations of the active columns by Gaussian elimination
// with partial pivoting (at most 3 unknowns here).
std::vector<double> solveWeightedLeastSquares(const std::vector<std::vector<double>>& x,
                                              const std::vector<double>& y, const std::vector<bool>& active) {
  const size_t k = active.size();
  std::vector<size_t> columns;
  for (size_t j = 0; j < k; ++j)
    if (active[j]) columns.push_back(j);
  const size_t m = columns.size();
  std::vector<std::vector<double>> a(m, std::vector<double>(m + 1, 0.0));
  for (size_t row = 0; row < x.size(); ++row) {
    const double weight = 1.0 / (y[row] * y[row]);
    for (size_t i = 0; i < m; ++i) {
      for (size_t j = 0; j < m; ++j) a[i][j] += weight * x[row][columns[i]] * x[row][columns[j]];
      a[i][m] += weight * x[row][columns[i]] * y[row];
    }
  }
  for (size_t i = 0; i < m; ++i) {
    size_t pivot = i;
    for (size_t r = i + 1; r < m; ++r)
      if (std::fabs(a[r][i]) > std::fabs(a[pivot][i])) pivot = r;
    std::swap(a[i], a[pivot]);
    if (std::fabs(a[i][i]) < 1e-300) continue;   // a feature constant over the samples: left at 0
    for (size_t r = 0; r < m; ++r) {
      if (r == i) continue;
      const double factor = a[r][i] / a[i][i];
      for (size_t c = i; c <= m; ++c) a[r][c] -= factor * a[i][c];
    }
  }
  std::vector<double> solution(k, 0.0);
  for (size_t i = 0; i < m; ++i)
    solution[columns[i]] = std::fabs(a[i][i]) < 1e-300 ? 0.0 : a[i][m] / a[i][i];
  return solution;
}

nlohmann::json toJson(const FamilyCoefficients& c) { return {{"build", c.build}, {"trace", c.trace}}; }

}  // namespace

CellShape cellShape(double triangles, const Bounds3& bounds) {
  CellShape shape;
  shape.triangles = triangles;
  if (!bounds.empty()) {
    const Vec3 d = bounds.diagonal();
    shape.extent = {double(d.x), double(d.y), double(d.z)};
  }
  return shape;
}

CellShape cellShape(const MeshView& mesh) {
  Bounds3 bounds;
  for (uint32_t t = 0; t < mesh.triangleCount; ++t) bounds.extend(mesh.triangleBounds(t));
  return cellShape(double(mesh.triangleCount), bounds);
}

const std::vector<int>& candidateGridResolutions() {
  static const std::vector<int> resolutions{2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64, 96, 128, 192, 256};
  return resolutions;
}

std::vector<double> buildFeatures(const AcceleratorCandidate& candidate, const CellShape& cell) {
  const double n = std::max(1.0, cell.triangles);
  if (candidate.family == "grid") {
    const auto r = gridResolution(candidate, cell);
    return {1.0, n, double(r[0]) * r[1] * r[2]};
  }
  return {1.0, n, n * log2Triangles(cell)};
}

std::vector<double> traceFeatures(const AcceleratorCandidate& candidate, const CellShape& cell) {
  const double n = std::max(1.0, cell.triangles);
  if (candidate.family == "grid") {
    const auto r = gridResolution(candidate, cell);
    const double voxels = double(r[0]) * r[1] * r[2];
    return {1.0, (r[0] + r[1] + r[2]) / 3.0, n / voxels};
  }
  return {1.0, log2Triangles(cell)};
}

std::vector<double> fitNonNegativeRelative(const std::vector<std::vector<double>>& features,
                                           const std::vector<double>& measured) {
  if (features.empty() || features.size() != measured.size())
    throw std::invalid_argument("fit: no samples, or features and measurements of different lengths");
  const size_t k = features.front().size();
  std::vector<bool> active(k, true);
  for (;;) {
    std::vector<double> c = solveWeightedLeastSquares(features, measured, active);
    size_t worst = k;
    for (size_t j = 0; j < k; ++j)
      if (active[j] && c[j] < 0 && (worst == k || c[j] < c[worst])) worst = j;
    if (worst == k) return c;
    active[worst] = false;   // a negative cost per feature is an artefact of noise
  }
}

CostModel CostModel::builtIn() {
  // `portico bench calibrate` on the 2-core development machine (Debian
  // bookworm VM), trace passes timed by thread CPU time: 25 cells (22 of
  // l-shape, 3 halls), 20 000 photon-like rays each. bvh comes from a later
  // run with the current bvh build (12 cells of soda-hall and a 3 000-
  // triangle hall), scaled by the ratio of the two runs' kd:sah predictions
  // for 10 000 triangles (trace x0.749, build x0.961), so that every family
  // is on one machine's scale.
  CostModel model;
  model.origin = "built-in (development machine)";
  model.families["grid"] = {{0.001955, 2.644e-05, 1.85e-05}, {232.5, 4.343, 0.7417}};
  model.families["hgrid"] = {{0, 0.0001609, 2.485e-05}, {84.98, 39.91}};
  model.families["kd:median"] = {{0, 0.0005673, 0}, {0, 81.87}};
  model.families["kd:sah"] = {{0, 0.0001917, 4.85e-05}, {33.76, 23.71}};
  model.families["kd:bbox"] = {{0, 0, 0.0001467}, {0, 58.29}};
  model.families["bvh"] = {{0.0061, 7.44e-05, 5.14e-06}, {24.08, 11.22}};
  return model;
}

void CostModel::check(const std::string& where) const {
  for (const char* family : kFamilies) {
    auto it = families.find(family);
    if (it == families.end()) throw std::runtime_error(where + ": no coefficients for " + family);
    const AcceleratorCandidate probe{family, family, 8};
    const CellShape cell{1000, {1, 1, 1}};
    const auto& c = it->second;
    if (c.build.size() != buildFeatures(probe, cell).size() || c.trace.size() != traceFeatures(probe, cell).size())
      throw std::runtime_error(where + ": wrong number of coefficients for " + family);
    for (const std::vector<double>* coefficients : {&c.build, &c.trace})
      for (double v : *coefficients)
        if (!std::isfinite(v) || v < 0)
          throw std::runtime_error(where + ": negative or non-finite coefficient for " + family);
  }
}

CostModel CostModel::load(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("calibration " + path + ": cannot be read");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const std::exception& e) {
    throw std::runtime_error("calibration " + path + ": not JSON (" + e.what() + ")");
  }
  if (!j.is_object() || j.value("version", 0) != kCalibrationVersion)
    throw std::runtime_error("calibration " + path + ": not a version " + std::to_string(kCalibrationVersion) +
                             " calibration (run `portico bench calibrate` again)");
  CostModel model;
  try {
    model.origin = j.value("origin", path);
    for (const auto& [family, c] : j.at("families").items())
      model.families[family] = {c.at("build").get<std::vector<double>>(), c.at("trace").get<std::vector<double>>()};
  } catch (const std::exception& e) {
    throw std::runtime_error("calibration " + path + ": malformed (" + e.what() + ")");
  }
  const CostModel builtInModel = builtIn();
  for (const char* family : kNewerFamilies)
    if (!model.families.count(family)) {
      model.families[family] = builtInModel.families.at(family);
      model.origin += std::string(" (") + family + ": built-in)";
    }
  model.check("calibration " + path);
  return model;
}

void CostModel::save(const std::string& path) const {
  check("calibration to save");
  nlohmann::json j;
  j["version"] = kCalibrationVersion;
  j["origin"] = origin;
  j["units"] = "build: ms; trace: ns per ray";
  for (const auto& [family, c] : families) j["families"][family] = toJson(c);
  writeFileAtomically(path, j.dump(2) + "\n");
}

std::string CostModel::defaultPath() {
  if (const char* explicitPath = std::getenv("PORTICO_CALIBRATION"); explicitPath && *explicitPath)
    return explicitPath;
  if (const char* cache = std::getenv("XDG_CACHE_HOME"); cache && *cache)
    return std::string(cache) + "/portico/calibration.json";
  const char* home = std::getenv("HOME");
  return std::string(home && *home ? home : "/tmp") + "/.cache/portico/calibration.json";
}

CostModel CostModel::loadDefault() {
  const std::string path = defaultPath();
  std::error_code error;
  return std::filesystem::exists(path, error) ? load(path) : builtIn();
}

std::vector<AcceleratorCandidate> CostModel::candidates(const CellShape& cell) const {
  std::vector<AcceleratorCandidate> list{{"grid", "grid", 0}};
  const double voxelBudget = std::max(kMinVoxelBudget, kMaxVoxelsPerTriangle * cell.triangles);
  for (int r : candidateGridResolutions()) {
    const AcceleratorCandidate grid{"grid:res=" + std::to_string(r), "grid", r};
    const auto res = gridResolution(grid, cell);
    if (double(res[0]) * res[1] * res[2] > voxelBudget) break;
    list.push_back(grid);
  }
  for (const char* family : kFamilies)
    if (std::string(family) != "grid") list.push_back({family, family, 0});
  return list;
}

CostPrediction CostModel::predict(const AcceleratorCandidate& candidate, const CellShape& cell) const {
  const FamilyCoefficients& c = families.at(candidate.family);
  CostPrediction p;
  p.candidate = candidate;
  p.buildMs = dot(c.build, buildFeatures(candidate, cell));
  p.traceNsPerRay = dot(c.trace, traceFeatures(candidate, cell));
  return p;
}

double CostModel::choiceWeight(const AcceleratorCandidate& candidate) {
  return candidate.spec == "grid" ? 1.0 - kPlainGridPreference : 1.0;
}

CostPrediction CostModel::choose(const CellShape& cell, double rays) const {
  CostPrediction best;
  double bestMs = std::numeric_limits<double>::infinity();
  for (const AcceleratorCandidate& candidate : candidates(cell)) {
    const CostPrediction p = predict(candidate, cell);
    const double weighed = p.totalMs(rays) * choiceWeight(candidate);
    if (weighed < bestMs) bestMs = weighed, best = p;
  }
  return best;
}

CostPrediction CostModel::predictSpec(const std::string& spec, const CellShape& cell) const {
  for (const AcceleratorCandidate& candidate : candidates(cell))
    if (candidate.spec == spec) return predict(candidate, cell);
  CostPrediction unknown;
  unknown.candidate.spec = spec;
  unknown.traceNsPerRay = -1;
  return unknown;
}

}  // namespace portico
