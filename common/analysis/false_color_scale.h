// The false-colour scale of portico's lighting pictures (work-plane plans
// in lux, luminance images in cd/m^2), in the manner of Radiance's
// `falsecolor`: a linear scale from 0 to a maximum, or (`decades` > 0, its
// `-log N`) a logarithmic one over that many decades below the maximum,
// coloured along a spectrum from dark violet through blue, cyan, green and
// yellow to red; values above the maximum take its colour, values below a
// logarithmic scale's bottom the bottom's. The legend labels `steps` equal
// intervals of the scale.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace portico {

using Rgb8 = std::array<uint8_t, 3>;

struct FalseColorScale {
  double maximum = 1000;   // the value coloured red; > 0
  int steps = 8;           // legend intervals
  std::string unit = "lx";
  int decades = 0;         // 0: linear from 0; N > 0: logarithmic from maximum / 10^N

  // Where `value` lies on the scale, 0 (bottom) to 1 (maximum), clamped; NaN as 0.
  double positionOf(double value) const;
  // The value at position t in [0, 1] (the inverse of positionOf).
  double valueAt(double t) const;
  // The colour of `value`: spectrumColor(positionOf(value)).
  Rgb8 colorOf(double value) const;
  // The legend's values: valueAt(k / steps) for k = 0 .. steps (linear: 0,
  // maximum / steps, ..., maximum).
  std::vector<double> legendValues() const;
  // A legend value as printed: "0", "125", "62.5", "1.5k" for 1500 and up.
  static std::string label(double value);
};

// The colour at t in [0, 1] along the spectrum.
Rgb8 spectrumColor(double t);

// The automatic top of a scale for `values`: their 95th percentile (the
// non-finite left out) rounded up by roundScaleMaximum. Not their largest:
// a sensor under a lamp, or the lamp seen in an image, would squeeze
// everything else into the bottom colours; those few take the top colour.
double automaticScaleMaximum(std::vector<double> values);

// The smallest "round" number (1, 2, 2.5 or 5 times a power of ten) at or
// above `value`: the maximum of an automatic scale; 1 when value <= 0.
double roundScaleMaximum(double value);

}  // namespace portico
