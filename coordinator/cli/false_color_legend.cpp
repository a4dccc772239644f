#include "coordinator/cli/false_color_legend.h"

namespace portico::cli {

namespace {

constexpr int kBarWidth = 28;
constexpr int kStepHeight = 40;   // pixels per legend interval
constexpr int kBarTop = kTextHeight + 12;   // below the unit

}  // namespace

int legendHeight(const FalseColorScale& scale) { return kBarTop + kStepHeight * scale.steps + kTextHeight; }

void drawLegend(Canvas& canvas, int left, int top, const FalseColorScale& scale) {
  const int barTop = top + kBarTop, barHeight = kStepHeight * scale.steps;
  canvas.text(left, top, scale.unit, kBlack);
  for (int y = 0; y <= barHeight; ++y) {
    const Rgb8 c = spectrumColor(double(barHeight - y) / barHeight);
    canvas.fill(left, barTop + y, left + kBarWidth - 1, barTop + y, {c[0], c[1], c[2]});
  }
  const std::vector<double> values = scale.legendValues();
  for (size_t k = 0; k < values.size(); ++k) {
    const int y = barTop + barHeight - int(k) * kStepHeight;
    canvas.line(left + kBarWidth, y, left + kBarWidth + 5, y, kBlack, 1, false);
    const std::string label = FalseColorScale::label(values[k]) + (k + 1 == values.size() ? "+" : "");
    canvas.text(left + kBarWidth + 9, y - kTextHeight / 2, label, kBlack);
  }
}

}  // namespace portico::cli
