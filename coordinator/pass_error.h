// The error estimate of a job rendered in passes (coordinator/render_passes.h):
// each pass is an independent image of the same expectation (its own seed),
// so the spread of a block's per-pass means says how far the average of the
// passes can be from that expectation. For each 16x16 block (the block rule
// of common/image/block_rule.h), the relative standard error of its mean:
// standard deviation of the per-pass block means / sqrt(passes) / mean; the
// job's estimate is the root mean square over the blocks brighter than 5 %
// of the image mean. It measures noise only: a bias every pass shares (the
// photon map's density estimate) is invisible to it.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "common/transport/film.h"

namespace portico {

// Per block, over the passes so far: the sum of the pass's block sums
// (radiance, R + G + B over the block's pixels) and the sum of squared
// deviations from their running mean (Welford's M2), which stays accurate
// where sum-of-squares minus square-of-sum would cancel.
struct PassBlockStatistics {
  std::vector<double> sums;
  std::vector<double> deviations;
};

struct PassError {
  std::optional<double> estimate;   // none before two passes, or when no block is bright enough
  int blocksUsed = 0;
};

// The film holds the sum of `passes` passes (fixed point, JobStore::film);
// adds the last pass's block sums (the film's less those of the passes
// before it) to `statistics` and returns the estimate after it. Deterministic:
// the same film and statistics give the same bits.
PassError addPassAndEstimate(const std::vector<FixedRgb>& film, uint32_t width, uint32_t height, uint32_t passes,
                             PassBlockStatistics& statistics);

}  // namespace portico
