// `--accel auto` in the worker: which structure to build for a cell, and
// when to rebuild it with another.
//
// A cell's rays are not known when it is first loaded: the photons that will
// reach it through portals are still elsewhere. The choice starts from the
// rays the cell is expected to trace now (the scheduler's pending work for
// the cell, times the rays traced per unit of work, learnt from past leases)
// and is revisited at each later lease of the cell: when the rays still
// expected from its pending work make another structure's build pay for
// itself with a margin, the cell is rebuilt (in the render pass, where a
// cell's pixels come in many leases, a busy cell is rebuilt once the rest
// of its queue is worth it). Every candidate returns the same hits, so
// rebuilding never changes a bit.
#pragma once

#include <algorithm>
#include <cstdint>
#include <optional>
#include <string>

#include "common/accel/cost_model.h"

namespace portico {

class AcceleratorChooser {
 public:
  explicit AcceleratorChooser(CostModel model) : model_(std::move(model)) {}

  const CostModel& model() const { return model_; }

  // Rays the cell is expected to trace for this much pending work.
  double expectedRays(bool renderPhase, int64_t cellWork) const {
    return double(std::max<int64_t>(cellWork, 1)) * raysPerWork_[renderPhase ? 1 : 0];
  }
  // After a lease: rays traced for the work it held.
  void learn(bool renderPhase, int64_t leaseWork, int64_t raysTraced);

  // The structure for a cell that is not loaded yet.
  CostPrediction firstChoice(const CellShape& cell, double expectedRays) const {
    return model_.choose(cell, expectedRays);
  }
  // A structure worth rebuilding the cell with, if any: one whose build plus
  // tracing of `futureRays` beats tracing them with `currentSpec` by a margin.
  std::optional<CostPrediction> betterChoice(const std::string& currentSpec, const CellShape& cell,
                                             double futureRays) const;

 private:
  CostModel model_;
  // Rays per unit of the scheduler's work: a photon bounces a few times in a
  // cell; a camera sample spawns shadow and gather rays. Learnt as leases finish.
  double raysPerWork_[2] = {2.0, 8.0};
  bool learnt_[2] = {false, false};
};

}  // namespace portico
