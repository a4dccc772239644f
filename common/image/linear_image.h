// A linear RGB float image: what a job's film becomes.
#pragma once

#include <cstdint>
#include <vector>

namespace portico {

struct LinearImage {
  uint32_t width = 0, height = 0;
  std::vector<float> rgb;   // row 0 at the top, 3 floats per pixel
};

}  // namespace portico
