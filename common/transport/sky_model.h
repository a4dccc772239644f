// The sky and the sun of a job's daylight (DaylightSettings): the sky's
// radiance in any direction, and the sun as a directional light. Units are
// those of lamps' radiance (W m^-2 sr^-1 per RGB channel), with luminance =
// 179 lm/W times Rec. 709 Y (the white efficacy of the Radiance lighting
// software): a clear sky's zenith of 5 000 cd/m^2 is about 28, the sun's
// 100 000 lx are 560.
//
// * Uniform: one radiance in every direction, below the horizon too (as
//   Mitsuba's `constant` emitter): the sky of exact validations.
// * Preetham: A. J. Preetham, P. Shirley, B. Smits, "A practical analytic
//   model for daylight" (SIGGRAPH 1999): Perez's luminance and chromaticity
//   distributions with the paper's coefficients for turbidity T, converted
//   from CIE xyY to linear Rec. 709 RGB.
// * Overcast: the CIE overcast sky, L(theta) = Lz (1 + 2 cos theta) / 3,
//   white, with Lz giving 10 000 lx on a horizontal plane.
// Below the horizon, Preetham's and the overcast sky show a ground of albedo
// 0.2, Lambertian and unshadowed: radiance 0.2 E / pi, with E the sky's and
// the sun's illuminance on it.
// The sun's irradiance, unless given, is 128 000 lx outside the atmosphere
// through Rayleigh and aerosol (Angstrom, beta from T as in Preetham's
// paper) extinction along the Kasten-Young air mass, per channel at 610,
// 550 and 465 nm: an approximation, reddening and dimming towards the
// horizon. The sun is a direction (no 0.53 degree disc).
#pragma once

#include <array>
#include <optional>
#include <string>

#include "common/job/job_settings.h"
#include "common/math.h"

namespace portico {

// The unit direction towards the sun: azimuth from +Z towards +X,
// elevation above the horizontal plane (+Y up).
Vec3 sunDirection(float azimuthDegrees, float elevationDegrees);

class SkyModel {
 public:
  explicit SkyModel(const DaylightSettings& settings);
  bool hasSky() const { return kind_ != DaylightSettings::Sky::None; }
  bool hasSun() const { return sun_; }
  // Radiance arriving from unit direction `towardsSky` (pointing away from
  // the receiver, into the sky).
  Vec3 radiance(const Vec3& towardsSky) const;
  const Vec3& sunDirection() const { return sunDirection_; }
  const Vec3& sunIrradiance() const { return sunIrradiance_; }
  // The sky's irradiance on a plane facing unit direction n (from the
  // hemisphere about n), by a fixed stratified quadrature: the same bits
  // wherever it is computed.
  Vec3 irradianceFacing(const Vec3& n) const;
  // The sky's illuminance (lux) on an unobstructed horizontal plane, in
  // closed form: pi L for the uniform sky (its upper hemisphere), 7 pi Lz / 9
  // for the CIE overcast sky (10 000 lx); nullopt for Preetham's sky and
  // for none.
  std::optional<double> horizontalSkyLux() const;

 private:
  Vec3 preetham(const Vec3& towardsSky) const;
  void setUpPreetham(const DaylightSettings& settings);
  DaylightSettings::Sky kind_;
  Vec3 uniform_;
  bool sun_;
  Vec3 sunDirection_;
  Vec3 sunIrradiance_;
  // Preetham: Perez coefficients A..E for Y, x, y; zenith Y (radiance
  // units), x, y; and each distribution's value at the zenith.
  std::array<std::array<float, 5>, 3> perez_{};
  std::array<float, 3> zenith_{}, perezAtZenith_{};
  float overcastZenith_ = 0;
  Vec3 groundRadiance_;
};

// The sun's irradiance at `elevationDegrees` for turbidity T (the model above).
Vec3 modelledSunIrradiance(float elevationDegrees, float turbidity);

// The one-line problem with daylight settings ("" when none), naming the option.
std::string daylightProblem(const DaylightSettings& settings);

}  // namespace portico
