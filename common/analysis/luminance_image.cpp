#include "common/analysis/luminance_image.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "common/analysis/sensor.h"

namespace portico {

LinearImage luminanceImage(const LinearImage& radiance) {
  LinearImage image = radiance;
  for (size_t p = 0; p + 2 < image.rgb.size(); p += 3) {
    const auto value = float(kLuminousEfficacy * rec709Y(Vec3(radiance.rgb[p], radiance.rgb[p + 1], radiance.rgb[p + 2])));
    image.rgb[p] = image.rgb[p + 1] = image.rgb[p + 2] = value;
  }
  return image;
}

std::vector<double> luminanceValues(const LinearImage& luminance) {
  std::vector<double> values;
  for (size_t p = 0; p < luminance.rgb.size(); p += 3) values.push_back(luminance.rgb[p]);
  return values;
}

}  // namespace portico
