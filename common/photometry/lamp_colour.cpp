#include "common/photometry/lamp_colour.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "common/analysis/sensor.h"

namespace portico {

Chromaticity planckianChromaticity(double kelvin) {
  const double t = std::clamp(kelvin, kMinColourTemperature, kMaxColourTemperature);
  const double t1 = 1e3 / t, t2 = t1 * t1, t3 = t2 * t1;   // in 1/kK, as Kang et al. write the fits
  const double x = t <= 4000.0 ? -0.2661239 * t3 - 0.2343589 * t2 + 0.8776956 * t1 + 0.179910
                               : -3.0258469 * t3 + 2.1070379 * t2 + 0.2226347 * t1 + 0.240390;
  const double x2 = x * x, x3 = x2 * x;
  double y;
  if (t <= 2222.0)
    y = -1.1063814 * x3 - 1.34811020 * x2 + 2.18555832 * x - 0.20219683;
  else if (t <= 4000.0)
    y = -0.9549476 * x3 - 1.37418593 * x2 + 2.09137015 * x - 0.16748867;
  else
    y = 3.0817580 * x3 - 5.87338670 * x2 + 3.75112997 * x - 0.37001483;
  return {x, y};
}

Vec3 colourOfTemperature(double kelvin) {
  const Chromaticity c = planckianChromaticity(kelvin);
  // XYZ at Y = 1, then the XYZ -> linear Rec. 709 (D65) matrix of IEC 61966-2-1.
  const double X = c.x / c.y, Y = 1.0, Z = (1.0 - c.x - c.y) / c.y;
  const double r = 3.2404542 * X - 1.5371385 * Y - 0.4985314 * Z;
  const double g = -0.9692660 * X + 1.8760108 * Y + 0.0415560 * Z;
  const double b = 0.0556434 * X - 0.2040259 * Y + 1.0572252 * Z;
  return unitLuminanceColour(Vec3(float(std::max(r, 0.0)), float(std::max(g, 0.0)), float(std::max(b, 0.0))));
}

Vec3 unitLuminanceColour(const Vec3& rgb) { return rgb * float(1.0 / rec709Y(rgb)); }

Vec3 powerOfLumens(double lumens, const Vec3& colour) {
  return unitLuminanceColour(colour) * float(lumens / kLuminousEfficacy);
}

Vec3 radianceOfLumens(double lumens, const Vec3& colour, double area) {
  return unitLuminanceColour(colour) * float(lumens / (kLuminousEfficacy * M_PI * area));
}

double lumensOfPower(const Vec3& power) { return kLuminousEfficacy * rec709Y(power); }

std::string colourTemperatureProblem(double kelvin) {
  if (!(kelvin >= kMinColourTemperature && kelvin <= kMaxColourTemperature))
    return fmt::format("colour temperature {} K lies outside {}-{} K", kelvin, kMinColourTemperature,
                       kMaxColourTemperature);
  return {};
}

}  // namespace portico
