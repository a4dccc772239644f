// A luminaire's candela values on the angle grid of its photometric file
// (type C: vertical angle gamma from the nadir, 0 to 180 degrees; horizontal
// angle C around the nadir axis, 0 to 360 degrees, from the luminaire's C0
// direction towards its C90 direction), with the file's symmetry: the
// horizontal angles run 0 (one plane: the same all around), 0-90 (the four
// quadrants mirror each other), 0-180 (the two halves mirror each other
// across the C0-C180 plane), 90-270 (across the C90-C270 plane) or 0-360.
#pragma once

#include <string>
#include <vector>

namespace portico {

struct CandelaGrid {
  std::vector<double> vertical;     // degrees, increasing; from 0 or 90 to 90 or 180
  std::vector<double> horizontal;   // degrees, increasing; one of the ranges above
  std::vector<double> candela;      // horizontal-major: candela[h * vertical.size() + v]
  // The intensity in direction (gamma, c), degrees: linear between the
  // grid's angles, the horizontal angle folded by the symmetry, 0 outside
  // the vertical range.
  double at(double gamma, double c) const;
  // Why the grid is not one of the above ("" when it is).
  std::string problem() const;
};

}  // namespace portico
