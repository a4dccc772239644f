// Order-independent film accumulation. Each contribution is rounded to a
// fixed-point integer on its own and integers add associatively, so the sum
// per pixel is the same bits whatever order rays finish in, on however many
// workers, across retries.
#pragma once

#include <cmath>
#include <cstdint>
#include <unordered_map>

#include "common/math.h"

namespace portico {

// 2^-24 radiance units per step: resolves dim indirect light (1e-4) to 0.2 %,
// and an int64 holds 5e11 contributions of radiance 1000 before overflow.
constexpr double kFilmScale = 16777216.0;

struct FixedRgb {
  int64_t r = 0, g = 0, b = 0;
  FixedRgb& operator+=(const FixedRgb& o) { r += o.r; g += o.g; b += o.b; return *this; }
};

inline int64_t toFixed(float v) {
  // Non-finite or negative contributions are bugs upstream; never let them
  // poison a pixel (counted separately by the tracer).
  if (!(v > 0.0f) || !std::isfinite(v)) return 0;
  return static_cast<int64_t>(std::llround(static_cast<double>(v) * kFilmScale));
}

inline FixedRgb toFixed(const Vec3& v) { return {toFixed(v.x), toFixed(v.y), toFixed(v.z)}; }

inline float fromFixed(int64_t v) { return static_cast<float>(static_cast<double>(v) / kFilmScale); }

// Sparse per-pixel sums for one lease.
class FilmAccumulator {
 public:
  void add(uint32_t pixel, const Vec3& radiance) { sums_[pixel] += toFixed(radiance); }
  const std::unordered_map<uint32_t, FixedRgb>& sums() const { return sums_; }
  bool empty() const { return sums_.empty(); }

 private:
  std::unordered_map<uint32_t, FixedRgb> sums_;
};

}  // namespace portico
