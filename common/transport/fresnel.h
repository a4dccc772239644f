// Fresnel reflectance of smooth interfaces: a dielectric's (glass panes, a
// plastic's coating) and a conductor's (metals), unpolarised light.
#pragma once

#include <algorithm>
#include <cmath>

#include "common/math.h"

namespace portico {

// Entered at cosine cosIncident (either side: callers meet it from outside)
// with relative index eta >= 1; total internal reflection cannot happen.
inline float fresnelDielectric(float cosIncident, float eta) {
  const float cosI = std::clamp(std::abs(cosIncident), 0.0f, 1.0f);
  const float sin2T = (1.0f - cosI * cosI) / (eta * eta);
  if (sin2T >= 1.0f) return 1.0f;
  const float cosT = std::sqrt(1.0f - sin2T);
  const float parallel = (eta * cosI - cosT) / (eta * cosI + cosT);
  const float perpendicular = (cosI - eta * cosT) / (cosI + eta * cosT);
  return 0.5f * (parallel * parallel + perpendicular * perpendicular);
}

// A conductor of complex index eta + i k, met at cosine cosIncident (the
// exact expression for both polarisations, as Mitsuba's and pbrt's).
inline float fresnelConductor(float cosIncident, float eta, float k) {
  const float cos2 = std::clamp(cosIncident * cosIncident, 0.0f, 1.0f);
  const float cosI = std::sqrt(cos2);
  const float sin2 = 1.0f - cos2;
  const float eta2 = eta * eta, k2 = k * k;
  const float t0 = eta2 - k2 - sin2;
  const float a2b2 = std::sqrt(std::max(0.0f, t0 * t0 + 4.0f * eta2 * k2));
  const float a = std::sqrt(std::max(0.0f, 0.5f * (a2b2 + t0)));
  const float t1 = a2b2 + cos2, t2 = 2.0f * cosI * a;
  const float perpendicular = (t1 - t2) / (t1 + t2);
  const float t3 = cos2 * a2b2 + sin2 * sin2, t4 = t2 * sin2;
  const float parallel = perpendicular * (t3 - t4) / (t3 + t4);
  return 0.5f * (perpendicular + parallel);
}

// A metal given by the colour it reflects at normal incidence: the complex
// index whose normal reflectance is `reflectance` and whose edge tint is
// white (Gulbrandsen 2014, "Artist friendly metallic Fresnel", with g = 1),
// so it whitens towards grazing as real metals do.
struct ConductorIndex {
  Vec3 eta, k;
};
inline ConductorIndex conductorFromReflectance(const Vec3& reflectance) {
  ConductorIndex index;
  for (int c = 0; c < 3; ++c) {
    // r = 1 has no finite index; 0.9999 is white to the eye.
    const float r = std::clamp(reflectance[c], 0.0f, 0.9999f);
    const float n = (1.0f - r) / (1.0f + r);
    index.eta[c] = n;
    index.k[c] = std::sqrt(std::max(0.0f, (r * (n + 1.0f) * (n + 1.0f) - (n - 1.0f) * (n - 1.0f)) / (1.0f - r)));
  }
  return index;
}

inline Vec3 fresnelConductor(float cosIncident, const ConductorIndex& index) {
  return {fresnelConductor(cosIncident, index.eta.x, index.k.x), fresnelConductor(cosIncident, index.eta.y, index.k.y),
          fresnelConductor(cosIncident, index.eta.z, index.k.z)};
}

}  // namespace portico
