// The arithmetic both correlated multi-jittered sets share (Kensler,
// "Correlated Multi-Jittered Sampling", 2013): the camera's pixel
// positions (pixel_samples.h) and the patterns of a pixel's other random
// numbers (pixel_pattern.h), which differ only in how they permute.
#pragma once

#include <algorithm>
#include <cstdint>

namespace portico {

// count points on a columns x rows grid: columns the largest divisor of
// count not above its square root (count prime: 1 x count, N-rooks alone).
struct JitterGrid {
  uint32_t columns = 1, rows = 1;
};
inline JitterGrid jitterGrid(uint32_t count) {
  JitterGrid grid;
  for (uint32_t d = 1; d * d <= count; ++d)
    if (count % d == 0) grid.columns = d;
  grid.rows = count / grid.columns;
  return grid;
}

// One coordinate of a point in cell `cell` of `cells` along the axis, in
// its fine stratum `fine` of `fineCount` within that cell, jittered by
// `jitter` in [0, 1); below 1 however it rounds.
inline float multiJittered(uint32_t cell, uint32_t cells, uint32_t fine, uint32_t fineCount, float jitter) {
  return std::min((float(cell) + (float(fine) + jitter) / float(fineCount)) / float(cells), 0x1.fffffep-1f);
}

}  // namespace portico
