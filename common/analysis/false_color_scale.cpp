#include "common/analysis/false_color_scale.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace portico {

namespace {

// Stops of the spectrum, evenly spaced from t = 0 to t = 1.
constexpr std::array<Rgb8, 7> kStops{{
    {40, 0, 90},      // dark violet: no light
    {0, 0, 230},      // blue
    {0, 180, 230},    // cyan
    {0, 200, 0},      // green
    {230, 230, 0},    // yellow
    {255, 130, 0},    // orange
    {230, 0, 0},      // red: the maximum and above
}};

}  // namespace

Rgb8 spectrumColor(double t) {
  if (!(t > 0)) return kStops.front();   // also NaN
  if (t >= 1) return kStops.back();
  const double position = t * double(kStops.size() - 1);
  const size_t below = size_t(position);
  const double f = position - double(below);
  Rgb8 color;
  for (int c = 0; c < 3; ++c)
    color[c] = uint8_t(std::lround(kStops[below][c] + f * (double(kStops[below + 1][c]) - kStops[below][c])));
  return color;
}

double FalseColorScale::positionOf(double value) const {
  if (!(value > 0)) return 0;   // also NaN
  const double t = decades > 0 ? 1 + std::log10(value / maximum) / decades : value / maximum;
  return std::clamp(t, 0.0, 1.0);
}

double FalseColorScale::valueAt(double t) const {
  return decades > 0 ? maximum * std::pow(10.0, (t - 1) * decades) : maximum * t;
}

Rgb8 FalseColorScale::colorOf(double value) const { return spectrumColor(positionOf(value)); }

std::vector<double> FalseColorScale::legendValues() const {
  std::vector<double> values;
  for (int k = 0; k <= steps; ++k) values.push_back(valueAt(double(k) / steps));
  return values;
}

std::string FalseColorScale::label(double value) {
  if (value >= 1000) return fmt::format("{:g}k", std::round(value / 10.0) / 100.0);
  if (value >= 10 || value == 0) return fmt::format("{:g}", std::round(value * 10.0) / 10.0);
  return fmt::format("{:.3g}", value);
}

double automaticScaleMaximum(std::vector<double> values) {
  values.erase(std::remove_if(values.begin(), values.end(), [](double v) { return !std::isfinite(v); }), values.end());
  if (values.empty()) return roundScaleMaximum(0);
  const auto k = size_t(0.95 * double(values.size() - 1));
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return roundScaleMaximum(values[k]);
}

double roundScaleMaximum(double value) {
  if (!(value > 0) || !std::isfinite(value)) return 1;
  const double power = std::pow(10.0, std::floor(std::log10(value)));
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
    if (m * power >= value * (1 - 1e-12)) return m * power;
  return 10 * power;
}

}  // namespace portico
