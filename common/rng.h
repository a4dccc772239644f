// Counter-based random numbers: every value is a pure function of
// (seed, stream, path id, bounce, dimension), so no random state depends on
// the order in which cells, batches or workers are processed.
#pragma once

#include <cstdint>

namespace portico {

// Streams keep photon paths and camera paths from sharing numbers even when
// their path ids coincide.
enum class RandomStream : uint32_t { Photon = 1, Camera = 2, Light = 3 };

// Dimensions used within one bounce. Named so that two uses never collide.
namespace dim {
constexpr uint32_t LightChoice = 0;
constexpr uint32_t LightU = 1;
constexpr uint32_t LightV = 2;
constexpr uint32_t DirectionU = 3;
constexpr uint32_t DirectionV = 4;
constexpr uint32_t Roulette = 5;
constexpr uint32_t PixelX = 6;
constexpr uint32_t PixelY = 7;
constexpr uint32_t PixelShuffle = 8;   // keyed by pixel (not path) and step
// Reflect or pass at a glass pane, keyed by the ray's state (glassKey).
constexpr uint32_t GlassChoice = 9;
// The key of a pixel's pattern (pixel_pattern.h).
constexpr uint32_t PixelPattern = 10;
// A point on the sun's disc, where the direction dimensions are taken.
constexpr uint32_t SunU = 11;
constexpr uint32_t SunV = 12;
}  // namespace dim

// SplitMix64 finaliser: a bijective 64-bit mixer with full avalanche.
constexpr uint64_t mix64(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

constexpr uint64_t randomBits(uint64_t seed, RandomStream stream, uint64_t pathId, uint32_t bounce,
                              uint32_t dimension) {
  // Chain the mixer over each key part; each step is a bijection of the
  // running state, so distinct keys give independent-looking outputs.
  uint64_t h = mix64(seed ^ 0x9e3779b97f4a7c15ull);
  h = mix64(h ^ (static_cast<uint64_t>(stream) << 32 | bounce));
  h = mix64(h ^ pathId);
  h = mix64(h + dimension * 0x9e3779b97f4a7c15ull);
  return h;
}

// Uniform float in [0, 1): the top 24 bits, so 1.0 is never returned.
constexpr float randomUniform(uint64_t seed, RandomStream stream, uint64_t pathId, uint32_t bounce,
                              uint32_t dimension) {
  return static_cast<float>(randomBits(seed, stream, pathId, bounce, dimension) >> 40) *
         (1.0f / 16777216.0f);
}

}  // namespace portico
