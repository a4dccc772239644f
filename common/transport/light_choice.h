// A light chosen for a shading point and the probability it was chosen
// with (light_sampler.h, light_tree.h).
#pragma once

#include <cstdint>

namespace portico {

struct LightChoice {
  uint32_t light = 0;
  float probability = 0;   // 0: no light can contribute
};

}  // namespace portico
