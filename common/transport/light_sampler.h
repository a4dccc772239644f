// Chooses which area light a shading point samples. Weights follow each
// light's power over its squared distance (zero for lights facing away), so
// near, bright, visible-side lights get most samples; every light that can
// contribute keeps a nonzero probability, so the estimate stays unbiased.
#pragma once

#include <cstdint>
#include <vector>

#include "common/scene/scene_types.h"

namespace portico {

struct LightChoice {
  uint32_t light = 0;
  float probability = 0;   // 0: no light can contribute
};

class LightSampler {
 public:
  explicit LightSampler(const std::vector<AreaLight>& lights) : lights_(lights) {}
  // u in [0,1). Uses a thread-local scratch array; safe from several threads.
  LightChoice choose(const Vec3& point, const Vec3& normal, float u) const;

 private:
  const std::vector<AreaLight>& lights_;
};

}  // namespace portico
