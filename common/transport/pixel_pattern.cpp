#include "common/transport/pixel_pattern.h"

#include <algorithm>

#include "common/rng.h"
#include "common/transport/multi_jitter.h"

namespace portico {

namespace {
// Kensler's hashed permutation of [0, length): a bijection of the smallest
// power-of-two range holding it, walked until the value falls inside.
uint32_t permute(uint32_t i, uint32_t length, uint32_t p) {
  uint32_t w = length - 1;
  w |= w >> 1;
  w |= w >> 2;
  w |= w >> 4;
  w |= w >> 8;
  w |= w >> 16;
  do {
    i ^= p;
    i *= 0xe170893du;
    i ^= p >> 16;
    i ^= (i & w) >> 4;
    i ^= p >> 8;
    i *= 0x0929eb3fu;
    i ^= p >> 23;
    i ^= (i & w) >> 1;
    i *= 1u | p >> 27;
    i *= 0x6935fa69u;
    i ^= (i & w) >> 11;
    i *= 0x74dcb303u;
    i ^= (i & w) >> 2;
    i *= 0x9e501cc3u;
    i ^= (i & w) >> 2;
    i *= 0xc860a3dfu;
    i &= w;
    i ^= i >> 5;
  } while (i >= length);
  return (i + p) % length;
}

constexpr float kBelowOne = 0x1.fffffep-1f;

// Jitter within a stratum, one per (point, axis): one mix of the pattern's key.
float jitter(uint64_t key, uint32_t point, uint32_t axis) {
  return static_cast<float>(mix64(key ^ (uint64_t{point} << 2 | axis)) >> 40) * (1.0f / 16777216.0f);
}
}  // namespace

PixelPattern::PixelPattern(uint64_t seed, uint32_t pixel, PatternUse use, uint32_t count)
    : key_(randomBits(seed, RandomStream::Camera, pixel, static_cast<uint32_t>(use), dim::PixelPattern)),
      count_(count),
      columns_(jitterGrid(count).columns),
      rows_(jitterGrid(count).rows) {}

PatternPoint PixelPattern::point(uint32_t index) const {
  const uint32_t key = static_cast<uint32_t>(key_ >> 32);
  // Which point of the pattern this sample takes: a random pairing.
  const uint32_t s = permute(index, count_, key * 0x51633e2du);
  const uint32_t i = s % columns_, j = s / columns_;
  // Cell (i, j) of the columns x rows grid; within it the fine column of
  // `rows` and the fine row of `columns`, permuted so that each of the
  // count fine columns and fine rows is taken once (as pixel_samples.h).
  const uint32_t columnShift = permute(i, columns_, key * 0xa511e9b3u);
  const uint32_t rowShift = permute(j, rows_, key * 0x63d83595u);
  return {multiJittered(i, columns_, rowShift, rows_, jitter(key_, s, 0)),
          multiJittered(j, rows_, columnShift, columns_, jitter(key_, s, 1))};
}

float PixelPattern::value(uint32_t index) const {
  const uint32_t s = permute(index, count_, static_cast<uint32_t>(key_ >> 32) * 0x51633e2du);
  return std::min((float(s) + jitter(key_, s, 2)) / float(count_), kBelowOne);
}

}  // namespace portico
