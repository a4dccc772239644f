// Where a pixel's camera samples fall inside it: correlated multi-jittered
// positions (Kensler, "Correlated Multi-Jittered Sampling", 2013). spp = m x n
// with m the largest divisor not above sqrt(spp): each sample lies in its
// own cell of an m x n grid over the pixel (2-D stratified), and in its own
// of spp columns and of spp rows (N-rooks), so a pixel cut by an edge at any
// angle (a bright light's) sees its coverage evenly. With a prime spp it is
// N-rooks alone.
//
// Determinism: the positions depend only on the seed, the pixel and spp.
#pragma once

#include <cstdint>
#include <vector>

namespace portico {

struct PixelSample {
  float x, y;   // in [0, 1) within the pixel
};

// spp positions for `pixel`, sample s at [s]; `scratch` avoids allocations.
void pixelSamples(uint64_t seed, uint32_t pixel, uint32_t spp, std::vector<PixelSample>& samples,
                  std::vector<uint32_t>& scratch);

}  // namespace portico
