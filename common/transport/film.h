// Order-independent film accumulation. Each contribution is rounded to a
// fixed-point integer on its own and integers add associatively, so the sum
// per pixel is the same bits whatever order rays finish in, on however many
// workers, across retries.
#pragma once

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <unordered_map>

#include <fmt/format.h>

#include "common/math.h"

namespace portico {

// 2^-24 radiance units per step: resolves dim indirect light (1e-4) to 0.2 %.
constexpr double kFilmScale = 16777216.0;
// A pixel's sum stays at or below 2^62 steps, a value of 2.7e11: an int64
// then never wraps (two sums in range add without overflow), and a sum
// beyond it is refused, never stored. Radiance that bright comes from
// emission far beyond any physical light (the sun's disc is about 2e7
// W/m^2/sr); the job fails saying so rather than show wrapped, negative pixels.
constexpr int64_t kFilmMaxSum = int64_t(1) << 62;
constexpr double kFilmMaxValue = double(kFilmMaxSum) / kFilmScale;

struct FilmRangeError : std::runtime_error {
  FilmRangeError()
      : std::runtime_error(fmt::format("a pixel's radiance exceeds the film's range ({:.2g}): the scene's light "
                                       "emission is far too bright; scale it down",
                                       kFilmMaxValue)) {}
};

struct FixedRgb {
  int64_t r = 0, g = 0, b = 0;
  FixedRgb& operator+=(const FixedRgb& o) { r += o.r; g += o.g; b += o.b; return *this; }
  // Adds `o` if every channel stays within kFilmMaxSum (sums are never
  // negative); false, and nothing added, otherwise.
  bool addWithinRange(const FixedRgb& o) {
    int64_t nr, ng, nb;
    if (__builtin_add_overflow(r, o.r, &nr) || __builtin_add_overflow(g, o.g, &ng) ||
        __builtin_add_overflow(b, o.b, &nb) || nr > kFilmMaxSum || ng > kFilmMaxSum || nb > kFilmMaxSum ||
        nr < 0 || ng < 0 || nb < 0)
      return false;
    r = nr, g = ng, b = nb;
    return true;
  }
};

// Non-finite or negative contributions are bugs upstream; never let them
// poison a pixel (counted separately by the tracer). One beyond the film's
// range is kFilmMaxSum + 1, which no sum accepts.
inline int64_t toFixed(float v) {
  if (!(v > 0.0f) || !std::isfinite(v)) return 0;
  const double scaled = static_cast<double>(v) * kFilmScale;
  if (scaled > double(kFilmMaxSum)) return kFilmMaxSum + 1;
  return static_cast<int64_t>(std::llround(scaled));
}

inline FixedRgb toFixed(const Vec3& v) { return {toFixed(v.x), toFixed(v.y), toFixed(v.z)}; }

inline float fromFixed(int64_t v) { return static_cast<float>(static_cast<double>(v) / kFilmScale); }

// Sparse per-pixel sums for one lease.
class FilmAccumulator {
 public:
  // False, and nothing added, when the pixel's sum would leave the film's range.
  bool add(uint32_t pixel, const Vec3& radiance) { return sums_[pixel].addWithinRange(toFixed(radiance)); }
  const std::unordered_map<uint32_t, FixedRgb>& sums() const { return sums_; }
  bool empty() const { return sums_.empty(); }

 private:
  std::unordered_map<uint32_t, FixedRgb> sums_;
};

}  // namespace portico
