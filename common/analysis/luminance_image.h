// `--aov luminance`: a rendered image in photometric units. Each pixel's
// radiance (W m^-2 sr^-1 per RGB channel) becomes its luminance in cd/m^2,
// 179 lm/W x its Rec. 709 Y (common/analysis/sensor.h), written to all
// three channels: any viewer shows it grey, and EXR keeps the value.
#pragma once

#include <vector>

#include "common/image/linear_image.h"

namespace portico {

LinearImage luminanceImage(const LinearImage& radiance);

// The first channel's values (each pixel's luminance), for a scale.
std::vector<double> luminanceValues(const LinearImage& luminance);

}  // namespace portico
