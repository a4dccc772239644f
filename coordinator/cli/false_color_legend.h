// The legend of portico's false-colour pictures (plans in lux, luminance
// images in cd/m^2): the unit, a vertical bar with the scale's maximum at
// the top, a label at each step; the top label reads "MAX+" (values above
// take its colour).
#pragma once

#include "common/analysis/false_color_scale.h"
#include "coordinator/cli/png_canvas.h"

namespace portico::cli {

constexpr int kLegendWidth = 150;   // pixels, with its labels

// Pixels from the legend's top (the unit) to below its lowest label.
int legendHeight(const FalseColorScale& scale);

void drawLegend(Canvas& canvas, int left, int top, const FalseColorScale& scale);

}  // namespace portico::cli
