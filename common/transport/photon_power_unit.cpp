#include "common/transport/photon_power_unit.h"

#include <cmath>
#include <optional>

#include "common/transport/daylight_openings.h"
#include "common/transport/sampling.h"

namespace portico {

float photonPowerUnit(const SceneStore& scene, const JobSettings& settings, const DaylightEmitters* daylight) {
  // The emitters the planner shares photons among (queuePhotonEmission):
  // the lamps unless a daylight-factor job keeps them off, then daylight.
  double total = 0;
  if (lampsLit(settings))
    for (const AreaLight& light : scene.lights()) total += double(luminance(light.power()));
  std::optional<DaylightEmitters> made;
  if (settings.daylight.any() && !daylight) daylight = &made.emplace(scene, settings.daylight);
  if (settings.daylight.any())
    for (size_t e = 0; e < daylight->count(); ++e) total += double(luminance(daylight->power(e)));
  const float unit = float(total / double(settings.photons));
  return std::isfinite(unit) && unit > 0 && std::isnormal(unit) ? unit : 1.0f;
}

}  // namespace portico
