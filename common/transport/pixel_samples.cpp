#include "common/transport/pixel_samples.h"

#include <algorithm>

#include "common/rng.h"
#include "common/transport/multi_jitter.h"

namespace portico {

namespace {
// A per-pixel random permutation of [0, count) into `order[first, first + count)`;
// `salt` keeps the two permutations of a pixel apart.
void shuffle(uint64_t seed, uint32_t pixel, uint32_t salt, uint32_t count, uint32_t* order) {
  for (uint32_t i = 0; i < count; ++i) order[i] = i;
  for (uint32_t i = count; i > 1; --i) {
    const float u = randomUniform(seed, RandomStream::Camera, pixel, salt + i, dim::PixelShuffle);
    std::swap(order[i - 1], order[std::min(i - 1, static_cast<uint32_t>(u * float(i)))]);
  }
}
}  // namespace

void pixelSamples(uint64_t seed, uint32_t pixel, uint32_t spp, std::vector<PixelSample>& samples,
                  std::vector<uint32_t>& scratch) {
  const JitterGrid grid = jitterGrid(spp);
  const uint32_t m = grid.columns, n = grid.rows;
  scratch.resize(m + n);
  uint32_t* const columnShift = scratch.data();      // sx: one per grid column, shared by every row
  uint32_t* const rowShift = scratch.data() + m;     // sy: one per grid row, shared by every column
  shuffle(seed, pixel, 0, m, columnShift);
  shuffle(seed, pixel, 1u << 20, n, rowShift);
  samples.resize(spp);
  for (uint32_t s = 0; s < spp; ++s) {
    const uint32_t i = s % m, j = s / m;
    const uint64_t path = uint64_t(pixel) * spp + s;
    const float jitterX = randomUniform(seed, RandomStream::Camera, path, 0, dim::PixelX);
    const float jitterY = randomUniform(seed, RandomStream::Camera, path, 0, dim::PixelY);
    // Cell (i, j) of the m x n grid; within it, the fine column rowShift[j]
    // of n and the fine row columnShift[i] of m: over a grid column the
    // rows' shifts are a permutation, so the spp fine columns are each
    // taken once (and the fine rows likewise).
    samples[s].x = multiJittered(i, m, rowShift[j], n, jitterX);
    samples[s].y = multiJittered(j, n, columnShift[i], m, jitterY);
  }
}

}  // namespace portico
