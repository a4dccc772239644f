// Random numbers shared out over all of a pixel's samples: for each use
// (a pixel's light samples, its final-gather directions) the points of all
// its camera samples together form one correlated multi-jittered pattern
// (Kensler, "Correlated Multi-Jittered Sampling", 2013), so 16 samples of 4
// gather rays cover the hemisphere as 64 stratified directions, not as 64
// independent ones. Nearly every camera sample of a pixel lands on the same
// surface, so their directions and light points add up to one stratified
// estimate of the pixel's light.
//
// Point `index` of `count` is computed alone (Kensler's hashed permutations
// need no table), so a camera ray traced in another cell than its pixel's
// lease (after a portal) draws the same numbers. Each use's pattern pairs
// its points with the pixel's samples by its own random permutation: the
// pairing with pixel positions and with every other use is random, as the
// estimator needs to stay unbiased.
//
// Determinism: a point depends only on (seed, pixel, use, index, count).
#pragma once

#include <cstdint>

namespace portico {

// The uses that draw from a pixel pattern, each with its own numbers.
enum class PatternUse : uint32_t { LightChoice = 1, LightPoint = 2, GatherDirection = 3 };

struct PatternPoint {
  float u, v;   // in [0, 1)
};

// The pixel's pattern of `count` points for `use`.
class PixelPattern {
 public:
  PixelPattern(uint64_t seed, uint32_t pixel, PatternUse use, uint32_t count);
  // Point `index` (< count) of the 2-D pattern.
  PatternPoint point(uint32_t index) const;
  // Value `index` (< count) of the 1-D stratified set: one in each of
  // `count` equal intervals of [0, 1).
  float value(uint32_t index) const;

 private:
  uint64_t key_;
  uint32_t count_, columns_, rows_;   // columns_ x rows_ = count_
};

}  // namespace portico
