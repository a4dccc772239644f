// Sampling routines shared by photon emission, bounces and light sampling.
#pragma once

#include <cmath>

#include "common/math.h"

namespace portico {

// Cosine-weighted direction about unit normal n from two uniforms (Malley's
// method: uniform disc, projected up). pdf = cos(theta) / pi.
inline Vec3 sampleCosineHemisphere(const Vec3& n, float u1, float u2) {
  const float r = std::sqrt(u1);
  const float phi = 2.0f * kPi * u2;
  const float x = r * std::cos(phi), y = r * std::sin(phi);
  const float z = std::sqrt(std::max(0.0f, 1.0f - u1));
  Vec3 t, b;
  orthonormalBasis(n, t, b);
  return normalize(t * x + b * y + n * z);
}

// How far a ray's start is moved off or into a surface near p: large enough
// to clear float error at building scale (coordinates up to ~1 km), small
// against any real gap.
inline float surfaceOffset(const Vec3& p) {
  return 2e-5f * std::max({1.0f, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
}

// Offset for rays leaving a surface.
inline Vec3 offsetAlongNormal(const Vec3& p, const Vec3& n) { return p + n * surfaceOffset(p); }

inline float luminance(const Vec3& c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

}  // namespace portico
