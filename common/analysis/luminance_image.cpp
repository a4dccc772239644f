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

double luminancePercentile(const LinearImage& luminance, double fraction) {
  std::vector<float> values;
  for (size_t p = 0; p < luminance.rgb.size(); p += 3)
    if (std::isfinite(luminance.rgb[p])) values.push_back(luminance.rgb[p]);
  if (values.empty()) return 0;
  const auto k = size_t(std::clamp(fraction, 0.0, 1.0) * double(values.size() - 1));
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[k];
}

}  // namespace portico
