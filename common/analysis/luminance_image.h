// `--aov luminance`: a rendered image in photometric units. Each pixel's
// radiance (W m^-2 sr^-1 per RGB channel) becomes its luminance in cd/m^2,
// 179 lm/W x its Rec. 709 Y (common/analysis/sensor.h), written to all
// three channels: any viewer shows it grey, and EXR keeps the value.
#pragma once

#include "common/image/linear_image.h"

namespace portico {

LinearImage luminanceImage(const LinearImage& radiance);

// The luminance (first channel) that `fraction` of the pixels are at or
// under, non-finite pixels left out; 0 for an empty image. A false-colour
// scale's automatic maximum (fraction 0.95: lamps seen directly, a few
// pixels, do not squeeze the room into the scale's bottom colour).
double luminancePercentile(const LinearImage& luminance, double fraction);

}  // namespace portico
