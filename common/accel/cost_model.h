// `--accel auto`: a cost model that predicts, for one cell, the build time and
// the per-ray tracing time of each of portico's own structures, and picks the
// one with the smallest build + rays x per-ray time (the paper's conclusion,
// §7: classify structures by triangle count and the number of rays to cast).
//
// Only portico's own structures are candidates: they return identical hits,
// so the choice changes speed, never the image. Embree is left out because
// its hits differ from theirs in the last bits.
//
// The model is linear in a few features of the cell per structure family:
//   grid:res=R   build  ~ 1, n, voxels             trace ~ 1, mean voxels per axis, n / voxels
//   hgrid, kd:*, bvh  build ~ 1, n, n log2 n        trace ~ 1, log2 n
// (n = triangles; voxels from R and the cell's shape). The grid's terms give
// the U-shaped curve of the paper's Fig. 4: coarse grids test many triangles
// per voxel, fine ones cross many empty voxels and take long to build. The
// coefficients are calibrated on the machine (`portico bench calibrate`,
// stored as JSON and reused); built-in defaults were measured on the
// development machine.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "common/mesh_view.h"

namespace portico {

// What the model knows of a cell before loading it.
struct CellShape {
  double triangles = 0;
  std::array<double, 3> extent{0, 0, 0};   // of the cell's bounds
};

CellShape cellShape(double triangles, const Bounds3& bounds);
// From the mesh itself (its triangles' bounds).
CellShape cellShape(const MeshView& mesh);

// One structure with its parameters, as a spec string, and its family.
struct AcceleratorCandidate {
  std::string spec;      // "grid", "grid:res=24", "kd:sah", ...
  std::string family;    // "grid", "hgrid", "kd:median", "kd:sah", "kd:bbox", "bvh"
  int gridResolution = 0;  // R for grid:res=R; 0 for plain `grid` (its automatic resolution)
};

struct CostPrediction {
  AcceleratorCandidate candidate;
  double buildMs = 0;
  double traceNsPerRay = 0;
  double totalMs(double rays) const { return buildMs + rays * traceNsPerRay * 1e-6; }
};

// Coefficients per family: build (ms) and trace (ns per ray), each a dot
// product with the family's features.
struct FamilyCoefficients {
  std::vector<double> build;
  std::vector<double> trace;
};

class CostModel {
 public:
  // Measured on the development machine (see cost_model.cpp).
  static CostModel builtIn();
  // Reads a calibration written by save(); throws std::runtime_error naming
  // the file and the problem (unreadable, malformed, wrong version, missing
  // family). A family newer than the file (bvh) takes the built-in coefficients.
  static CostModel load(const std::string& path);
  // Written atomically (temporary file, then rename).
  void save(const std::string& path) const;
  // $PORTICO_CALIBRATION, else $XDG_CACHE_HOME/portico/calibration.json,
  // else ~/.cache/portico/calibration.json.
  static std::string defaultPath();
  // The calibration at defaultPath() when it exists, else builtIn().
  static CostModel loadDefault();

  // Every candidate the model knows for this cell: plain `grid` first, then
  // grid resolutions whose voxel count stays within a sane multiple of the
  // triangle count, then the other families.
  std::vector<AcceleratorCandidate> candidates(const CellShape& cell) const;
  CostPrediction predict(const AcceleratorCandidate& candidate, const CellShape& cell) const;
  // The cheapest candidate for `rays` rays (ties: the earlier candidate),
  // plain `grid` kept unless another is predicted cheaper by a margin.
  CostPrediction choose(const CellShape& cell, double rays) const;
  // What choose() multiplies a candidate's predicted cost by: below 1 for
  // the plain grid, 1 for the others.
  static double choiceWeight(const AcceleratorCandidate& candidate);
  // The prediction for a concrete spec string ("grid:res=24", "kd:sah", ...)
  // as listed by candidates(); nullopt-like: traceNsPerRay < 0 when unknown.
  CostPrediction predictSpec(const std::string& spec, const CellShape& cell) const;

  std::map<std::string, FamilyCoefficients> families;
  std::string origin;   // "built-in" or the calibration's description

 private:
  void check(const std::string& where) const;
};

// Features of a candidate on a cell, in the order of the coefficients.
std::vector<double> buildFeatures(const AcceleratorCandidate& candidate, const CellShape& cell);
std::vector<double> traceFeatures(const AcceleratorCandidate& candidate, const CellShape& cell);

// The grid resolutions candidates() considers.
const std::vector<int>& candidateGridResolutions();

// Least squares with relative error (rows weighted by 1/y^2), coefficients
// kept >= 0 by dropping the most negative one and refitting. Used by the
// calibration; exposed for its test.
std::vector<double> fitNonNegativeRelative(const std::vector<std::vector<double>>& features,
                                           const std::vector<double>& measured);

}  // namespace portico
