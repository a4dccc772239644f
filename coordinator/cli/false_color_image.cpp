#include "coordinator/cli/false_color_image.h"

#include <algorithm>

#include "common/analysis/luminance_image.h"
#include "common/analysis/result_paths.h"
#include "coordinator/cli/false_color_legend.h"

namespace portico::cli {

namespace {

constexpr int kLegendMargin = 16;   // pixels between the image and the legend, and above it

}  // namespace

Canvas drawFalseColorImage(const LinearImage& luminance, FalseColorScale scale, FalseColorScale* resolved) {
  if (!(scale.maximum > 0)) scale.maximum = automaticScaleMaximum(luminanceValues(luminance));
  if (resolved) *resolved = scale;
  const int width = int(luminance.width), height = int(luminance.height);
  Canvas canvas(width + kLegendMargin + kLegendWidth, std::max(height, legendHeight(scale) + 2 * kLegendMargin));
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const Rgb8 c = scale.colorOf(luminance.rgb[(size_t(y) * width + x) * 3]);
      canvas.set(x, y, {c[0], c[1], c[2]});
    }
  drawLegend(canvas, width + kLegendMargin, kLegendMargin, scale);
  return canvas;
}

std::string falseColorImagePath(const std::string& output) { return besideResults(output, ".falsecolor.png"); }

}  // namespace portico::cli
