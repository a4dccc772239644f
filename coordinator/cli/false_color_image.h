// `--falsecolor`: a luminance image (common/analysis/luminance_image.h) as
// a false-colour picture, in the manner of Radiance's `falsecolor`: each
// pixel coloured by its cd/m^2 on a FalseColorScale, the legend to the
// right of the image.
#pragma once

#include "common/analysis/false_color_scale.h"
#include "common/image/linear_image.h"
#include "coordinator/cli/png_canvas.h"

namespace portico::cli {

// The picture; pixel (x, y) of the image is pixel (x, y) of the canvas.
// A scale maximum <= 0 is chosen: automaticScaleMaximum of its pixels. `resolved` receives the scale
// drawn, when given.
Canvas drawFalseColorImage(const LinearImage& luminance, FalseColorScale scale,
                           FalseColorScale* resolved = nullptr);

// OUT.exr -> OUT.falsecolor.png beside it.
std::string falseColorImagePath(const std::string& output);

}  // namespace portico::cli
