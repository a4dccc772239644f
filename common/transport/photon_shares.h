// How a job's photons are shared out among the lights: in proportion to
// their power (luminance), by largest remainders so the shares sum exactly
// to the total. The coordinator's planner and the bench's in-core tracer
// both use it, so they emit the very same photon paths.
#pragma once

#include <cstdint>
#include <vector>

#include "common/scene/store/scene_types.h"

namespace portico {

std::vector<uint64_t> photonSharesOfLights(const std::vector<AreaLight>& lights, uint64_t total);
// The same for emitters of these powers (the scene's lights, then daylight
// emitters: common/transport/daylight_openings.h).
std::vector<uint64_t> photonSharesOfPowers(const std::vector<Vec3>& powers, uint64_t total);

}  // namespace portico
