#include "common/transport/sky_model.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "common/job/sun_time.h"
#include "common/transport/sampling.h"

namespace portico {

namespace {
constexpr float kWhiteEfficacy = 179.0f;          // lm/W: luminance = 179 * Y(RGB)
constexpr float kOvercastHorizontalLux = 10000.0f;
constexpr float kSolarLuxOutsideAtmosphere = 128000.0f;
constexpr float kDegrees = kPi / 180.0f;
constexpr float kGroundAlbedo = 0.2f;

Vec3 xyYToRgb(float x, float y, float luminance) {
  if (!(y > 0)) return Vec3(0);
  const float X = x / y * luminance, Z = (1.0f - x - y) / y * luminance;
  const Vec3 rgb(3.2406f * X - 1.5372f * luminance - 0.4986f * Z, -0.9689f * X + 1.8758f * luminance + 0.0415f * Z,
                 0.0557f * X - 0.2040f * luminance + 1.0570f * Z);
  return max(rgb, Vec3(0));
}

float perez(const std::array<float, 5>& c, float cosTheta, float gamma) {
  const float cosGamma = std::cos(gamma);
  return (1.0f + c[0] * std::exp(c[1] / cosTheta)) * (1.0f + c[2] * std::exp(c[3] * gamma) + c[4] * cosGamma * cosGamma);
}

// Preetham et al. 1999, appendix: zenith chromaticity as a cubic in the
// sun's zenith angle with coefficients quadratic in T.
float zenithChromaticity(const float (&m)[3][4], float t, float thetaSun) {
  const float th[4] = {thetaSun * thetaSun * thetaSun, thetaSun * thetaSun, thetaSun, 1.0f};
  const float tt[3] = {t * t, t, 1.0f};
  float sum = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j) sum += tt[i] * m[i][j] * th[j];
  return sum;
}
}  // namespace

Vec3 sunDirection(float azimuthDegrees, float elevationDegrees) {
  const float az = azimuthDegrees * kDegrees, el = elevationDegrees * kDegrees;
  return normalize(Vec3(std::sin(az) * std::cos(el), std::sin(el), std::cos(az) * std::cos(el)));
}

Vec3 modelledSunIrradiance(float elevationDegrees, float turbidity) {
  const float zenith = 90.0f - elevationDegrees;
  const float airMass = 1.0f / (std::cos(zenith * kDegrees) + 0.50572f * std::pow(96.07995f - zenith, -1.6364f));
  const float beta = 0.04608f * turbidity - 0.04586f;
  const float wavelengths[3] = {0.610f, 0.550f, 0.465f};   // micrometres
  Vec3 irradiance;
  for (int c = 0; c < 3; ++c) {
    const float rayleigh = 0.008735f * std::pow(wavelengths[c], -4.08f);
    const float aerosol = beta * std::pow(wavelengths[c], -1.3f);
    irradiance[c] = kSolarLuxOutsideAtmosphere / kWhiteEfficacy * std::exp(-airMass * (rayleigh + aerosol));
  }
  return irradiance;
}

SkyModel::SkyModel(const DaylightSettings& s)
    : kind_(s.sky), uniform_(s.skyRadiance), sun_(s.sun),
      sunDirection_(portico::sunDirection(s.sunAzimuthDegrees, s.sunElevationDegrees)) {
  if (sun_) sunIrradiance_ = maxComponent(s.sunIrradiance) > 0 ? s.sunIrradiance
                                                               : modelledSunIrradiance(s.sunElevationDegrees, s.turbidity);
  // The CIE overcast sky's horizontal illuminance is Lz * 7 pi / 9.
  overcastZenith_ = kOvercastHorizontalLux * 9.0f / (7.0f * kPi) / kWhiteEfficacy;
  if (kind_ == DaylightSettings::Sky::Preetham) setUpPreetham(s);
  // The ground: lit by the sky above it (the radiance below the horizon is
  // still zero here) and the sun.
  if (kind_ == DaylightSettings::Sky::Preetham || kind_ == DaylightSettings::Sky::Overcast) {
    Vec3 onGround = irradianceFacing(Vec3(0, 1, 0));
    if (sun_) onGround += sunIrradiance_ * std::max(0.0f, sunDirection_.y);
    groundRadiance_ = onGround * (kGroundAlbedo / kPi);
  }
}

void SkyModel::setUpPreetham(const DaylightSettings& s) {
  const float t = s.turbidity;
  perez_[0] = {0.1787f * t - 1.4630f, -0.3554f * t + 0.4275f, -0.0227f * t + 5.3251f, 0.1206f * t - 2.5771f,
               -0.0670f * t + 0.3703f};
  perez_[1] = {-0.0193f * t - 0.2592f, -0.0665f * t + 0.0008f, -0.0004f * t + 0.2125f, -0.0641f * t - 0.8989f,
               -0.0033f * t + 0.0452f};
  perez_[2] = {-0.0167f * t - 0.2608f, -0.0950f * t + 0.0092f, -0.0079f * t + 0.2102f, -0.0441f * t - 1.6537f,
               -0.0109f * t + 0.0529f};
  const float thetaSun = (90.0f - s.sunElevationDegrees) * kDegrees;
  const float chi = (4.0f / 9.0f - t / 120.0f) * (kPi - 2.0f * thetaSun);
  const float zenithKcd = (4.0453f * t - 4.9710f) * std::tan(chi) - 0.2155f * t + 2.4192f;
  static const float kX[3][4] = {{0.00166f, -0.00375f, 0.00209f, 0.0f},
                                 {-0.02903f, 0.06377f, -0.03202f, 0.00394f},
                                 {0.11693f, -0.21196f, 0.06052f, 0.25886f}};
  static const float kY[3][4] = {{0.00275f, -0.00610f, 0.00317f, 0.0f},
                                 {-0.04214f, 0.08970f, -0.04153f, 0.00516f},
                                 {0.15346f, -0.26756f, 0.06670f, 0.26688f}};
  zenith_ = {std::max(0.0f, zenithKcd) * 1000.0f / kWhiteEfficacy, zenithChromaticity(kX, t, thetaSun),
             zenithChromaticity(kY, t, thetaSun)};
  for (int k = 0; k < 3; ++k) perezAtZenith_[k] = perez(perez_[k], 1.0f, thetaSun);
}

Vec3 SkyModel::preetham(const Vec3& towardsSky) const {
  // Perez's 1/cos(theta) diverges at the horizon: the distribution is held
  // at its value 2.5 degrees up below that.
  const float cosTheta = std::max(towardsSky.y, 0.0436f);
  const float gamma = std::acos(std::clamp(dot(towardsSky, sunDirection_), -1.0f, 1.0f));
  float value[3];
  for (int k = 0; k < 3; ++k) value[k] = zenith_[k] * perez(perez_[k], cosTheta, gamma) / perezAtZenith_[k];
  return xyYToRgb(value[1], value[2], value[0]);
}

Vec3 SkyModel::radiance(const Vec3& towardsSky) const {
  switch (kind_) {
    case DaylightSettings::Sky::None: return Vec3(0);
    case DaylightSettings::Sky::Uniform: return uniform_;
    case DaylightSettings::Sky::Overcast:
      return towardsSky.y > 0 ? Vec3(overcastZenith_ * (1.0f + 2.0f * towardsSky.y) / 3.0f) : groundRadiance_;
    case DaylightSettings::Sky::Preetham: return towardsSky.y > 0 ? preetham(towardsSky) : groundRadiance_;
  }
  return Vec3(0);
}

Vec3 SkyModel::irradianceFacing(const Vec3& n) const {
  if (kind_ == DaylightSettings::Sky::None) return Vec3(0);
  if (kind_ == DaylightSettings::Sky::Uniform) return uniform_ * kPi;
  // Cosine-distributed midpoints of a 32 x 32 grid: E = pi * mean radiance.
  constexpr int kSteps = 32;
  Vec3 sum;
  for (int i = 0; i < kSteps; ++i)
    for (int j = 0; j < kSteps; ++j)
      sum += radiance(sampleCosineHemisphere(n, (i + 0.5f) / kSteps, (j + 0.5f) / kSteps));
  return sum * (kPi / float(kSteps * kSteps));
}

std::optional<double> SkyModel::horizontalSkyLux() const {
  const auto lux = [](const Vec3& rgb) {
    return double(kWhiteEfficacy) * (0.2126 * rgb.x + 0.7152 * rgb.y + 0.0722 * rgb.z);
  };
  if (kind_ == DaylightSettings::Sky::Uniform) return lux(uniform_) * kPi;
  if (kind_ == DaylightSettings::Sky::Overcast) return lux(Vec3(overcastZenith_)) * 7.0 * kPi / 9.0;
  return std::nullopt;
}

std::string daylightProblem(const DaylightSettings& s) {
  using Sky = DaylightSettings::Sky;
  if (s.sunTime) {
    // Its angles are resolved at submit (resolveSunTime), then checked here.
    if (const std::string problem = sunTimeProblem(*s.sunTime); !problem.empty()) return problem;
  } else if (s.sun) {
    if (!(std::isfinite(s.sunAzimuthDegrees) && s.sunAzimuthDegrees >= -360.0f && s.sunAzimuthDegrees <= 360.0f))
      return fmt::format("--sun: azimuth {} must be a number of degrees from -360 to 360", s.sunAzimuthDegrees);
    if (!(std::isfinite(s.sunElevationDegrees) && s.sunElevationDegrees > 0.0f && s.sunElevationDegrees <= 90.0f))
      return fmt::format("--sun: elevation {} must be above 0 and at most 90 degrees (the sun above the horizon)",
                         s.sunElevationDegrees);
  }
  if (s.sun) {
    if (!isFinite(s.sunIrradiance) || std::min({s.sunIrradiance.x, s.sunIrradiance.y, s.sunIrradiance.z}) < 0 ||
        maxComponent(s.sunIrradiance) > 1e7f)
      return fmt::format("--sun-irradiance {},{},{} must be numbers from 0 to 1e7", s.sunIrradiance.x,
                         s.sunIrradiance.y, s.sunIrradiance.z);
  } else if (maxComponent(s.sunIrradiance) > 0) {
    return "--sun-irradiance needs --sun";
  }
  if (s.sky == Sky::Preetham && !s.sun) return "--sky preetham needs --sun (the sky's brightest part is round the sun)";
  if (s.sky == Sky::Uniform &&
      (!isFinite(s.skyRadiance) || std::min({s.skyRadiance.x, s.skyRadiance.y, s.skyRadiance.z}) < 0 ||
       maxComponent(s.skyRadiance) > 1e7f))
    return fmt::format("--sky uniform:{},{},{}: the radiance must be numbers from 0 to 1e7", s.skyRadiance.x,
                       s.skyRadiance.y, s.skyRadiance.z);
  if (!(std::isfinite(s.turbidity) && s.turbidity >= 1.7f && s.turbidity <= 10.0f))
    return fmt::format("--turbidity {} must be from 1.7 to 10", s.turbidity);
  return "";
}

}  // namespace portico
