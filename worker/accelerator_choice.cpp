#include "worker/accelerator_choice.h"

#include <algorithm>

namespace portico {

namespace {
// A rebuild must win by this fraction of the current structure's predicted
// time: the model's error is of this order, and a rebuild that barely wins
// on paper may lose in fact.
constexpr double kRebuildMargin = 0.25;
// Weight of the newest lease in the running ratio of rays to work.
constexpr double kLearningRate = 0.2;
}  // namespace

void AcceleratorChooser::learn(bool renderPhase, int64_t leaseWork, int64_t raysTraced) {
  if (leaseWork <= 0 || raysTraced <= 0) return;
  const int phase = renderPhase ? 1 : 0;
  const double ratio = double(raysTraced) / double(leaseWork);
  raysPerWork_[phase] = learnt_[phase] ? (1 - kLearningRate) * raysPerWork_[phase] + kLearningRate * ratio : ratio;
  learnt_[phase] = true;
}

std::optional<CostPrediction> AcceleratorChooser::betterChoice(const std::string& currentSpec, const CellShape& cell,
                                                               double futureRays) const {
  const CostPrediction current = model_.predictSpec(currentSpec, cell);
  if (current.traceNsPerRay < 0) return std::nullopt;   // not one of the model's candidates
  const CostPrediction best = model_.choose(cell, futureRays);
  if (best.candidate.spec == currentSpec) return std::nullopt;
  const double keepMs = futureRays * current.traceNsPerRay * 1e-6;
  if (best.totalMs(futureRays) < (1.0 - kRebuildMargin) * keepMs) return best;
  return std::nullopt;
}

}  // namespace portico
