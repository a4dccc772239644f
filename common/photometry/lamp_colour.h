// Lamps given in photometric terms: a luminous flux in lumens and a colour
// (a colour temperature in kelvin or an RGB colour), turned into portico's
// radiometric units (W per RGB channel; luminance = 179 lm/W x Rec. 709 Y,
// docs/daylight.md). Shared by the building.json reader, the importer, the
// generator and the IES luminaires.
#pragma once

#include <string>

#include "common/math.h"

namespace portico {

// The colour temperatures colourOfTemperature accepts: the range of the
// Planckian-locus approximation it uses (Kang et al. 2002).
constexpr double kMinColourTemperature = 1667.0;
constexpr double kMaxColourTemperature = 25000.0;
// What a lamp given in lumens without a colour is: neutral white.
constexpr double kDefaultColourTemperature = 4000.0;

// CIE 1931 xy chromaticity of a Planckian radiator at `kelvin`, by the cubic
// fits of Kang, Moon, Hong, Lee, Cho & Kim, "Design of advanced color
// temperature control system for HDTV applications", J. Korean Physical
// Society 41 (6), 865-871 (2002): within 3e-4 of the locus computed from
// the CIE 1931 colour-matching functions over 1667-25000 K.
struct Chromaticity {
  double x = 0, y = 0;
};
Chromaticity planckianChromaticity(double kelvin);

// Linear Rec. 709 RGB of that radiator, scaled to Rec. 709 luminance Y = 1.
// Below about 1900 K the colour lies outside the Rec. 709 gamut: negative
// channels are clipped to 0 (then Y is 1 again).
Vec3 colourOfTemperature(double kelvin);

// An RGB colour (any scale, no negative channel, not black) scaled to Y = 1.
Vec3 unitLuminanceColour(const Vec3& rgb);

// The RGB power (W per channel) of `lumens` of light of `colour` (any
// scale): 179 lm/W x Y(power) = lumens.
Vec3 powerOfLumens(double lumens, const Vec3& colour);
// The uniform radiance (W m^-2 sr^-1 per channel) of a Lambertian emitter
// of `area` m^2 emitting `lumens` of `colour`: power / (pi area).
Vec3 radianceOfLumens(double lumens, const Vec3& colour, double area);
// Lumens of an RGB power: 179 x Y.
double lumensOfPower(const Vec3& power);

// The problem with a colour temperature, or "" when it is usable.
std::string colourTemperatureProblem(double kelvin);

}  // namespace portico
