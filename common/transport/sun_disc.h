// The sun's disc: 0.53 degrees across, seen from the earth. Shadow rays
// and photons of the sun take directions uniformly over it, so shadows
// have penumbrae, and camera rays that look into it see its radiance, the
// sun's irradiance over the disc's solid angle (a uniform disc, without
// limb darkening; Mitsuba's `sunsky` sun is a disc of the same size,
// its `directional` emitter a direction no camera sees).
#pragma once

#include <cmath>

#include "common/math.h"

namespace portico {

// 1 - cos of the disc's angular radius (0.265 degrees), kept apart from
// the cosine for precision: the cosine itself is 1 - 1.07e-5.
inline constexpr float kSunDiscOneMinusCosine = 1.0696e-5f;
inline constexpr float kSunDiscSolidAngle = 2.0f * kPi * kSunDiscOneMinusCosine;

// A direction uniformly distributed over the disc about unit `centre`.
inline Vec3 sampleSunDisc(const Vec3& centre, float u1, float u2) {
  const float oneMinusCosine = u1 * kSunDiscOneMinusCosine;
  const float sine = std::sqrt(oneMinusCosine * (2.0f - oneMinusCosine));
  const float phi = 2.0f * kPi * u2;
  Vec3 t, b;
  orthonormalBasis(centre, t, b);
  return normalize(centre * (1.0f - oneMinusCosine) + t * (sine * std::cos(phi)) + b * (sine * std::sin(phi)));
}

// Whether unit `direction` looks into the disc about unit `centre`.
inline bool insideSunDisc(const Vec3& direction, const Vec3& centre) {
  // 1 - cos from |d - c|^2 = 2 (1 - cos): no cancellation near the centre.
  const Vec3 d = direction - centre;
  return 0.5f * dot(d, d) <= kSunDiscOneMinusCosine;
}

}  // namespace portico
