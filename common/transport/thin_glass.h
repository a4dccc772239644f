// Thin glass: a pane so thin that light passing through leaves where it
// entered, in the direction it came (no refraction offset). Its two faces
// reflect by Fresnel; the light bouncing between them is summed in closed
// form, as Mitsuba's `thindielectric` does, so a pane reflects
// R' = 2R / (1 + R) of the light reaching it (R: one face's Fresnel
// reflectance) and lets through (1 - R') times its tint.
#pragma once

#include <algorithm>
#include <cmath>

#include "common/math.h"
#include "common/scene/store/scene_types.h"

namespace portico {

// Unpolarised Fresnel reflectance of a dielectric interface entered at
// cosine cosIncident (either side: a thin pane is symmetric) with relative
// index eta. Total internal reflection cannot happen from outside a pane.
inline float fresnelDielectric(float cosIncident, float eta) {
  const float cosI = std::clamp(std::abs(cosIncident), 0.0f, 1.0f);
  const float sin2T = (1.0f - cosI * cosI) / (eta * eta);
  if (sin2T >= 1.0f) return 1.0f;
  const float cosT = std::sqrt(1.0f - sin2T);
  const float parallel = (eta * cosI - cosT) / (eta * cosI + cosT);
  const float perpendicular = (cosI - eta * cosT) / (cosI + eta * cosT);
  return 0.5f * (parallel * parallel + perpendicular * perpendicular);
}

struct GlassResponse {
  float reflectance = 0;   // R', the same for every channel
  Vec3 transmittance;      // (1 - R') * tint
};

inline GlassResponse thinGlass(const Material& glass, float cosIncident) {
  const float r = fresnelDielectric(cosIncident, glass.ior);
  const float reflected = r < 1.0f ? 2.0f * r / (1.0f + r) : 1.0f;
  return {reflected, glass.transmittance * (1.0f - reflected)};
}

// The mirror direction of d about the unit normal n.
inline Vec3 reflect(const Vec3& d, const Vec3& n) { return d - n * (2.0f * dot(d, n)); }

}  // namespace portico
