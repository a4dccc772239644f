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
#include "common/transport/fresnel.h"
#include "common/scene/store/scene_types.h"

namespace portico {

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
