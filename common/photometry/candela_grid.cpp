#include "common/photometry/candela_grid.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace portico {

namespace {

// The horizontal angle the file gives for direction c (degrees in [0, 360)), by its symmetry.
double foldHorizontal(double c, double first, double last) {
  if (first == 90.0) {   // 90-270: mirrored across the C90-C270 plane
    if (c < 90.0) return 180.0 - c;
    if (c > 270.0) return 540.0 - c;
    return c;
  }
  if (last == 90.0) {    // quadrants
    if (c > 180.0) c = 360.0 - c;
    return c > 90.0 ? 180.0 - c : c;
  }
  if (last == 180.0) return c > 180.0 ? 360.0 - c : c;
  return c;              // 0-360 (or one plane)
}

// Linear interpolation of `values` (stride apart) at `x` among `angles`, which contain x.
double interpolate(const std::vector<double>& angles, double x, const double* values, size_t stride) {
  if (angles.size() == 1) return values[0];
  const size_t upper = std::min<size_t>(
      std::max<size_t>(size_t(std::upper_bound(angles.begin(), angles.end(), x) - angles.begin()), 1),
      angles.size() - 1);
  const size_t lower = upper - 1;
  const double t = std::clamp((x - angles[lower]) / (angles[upper] - angles[lower]), 0.0, 1.0);
  return values[lower * stride] * (1.0 - t) + values[upper * stride] * t;
}

bool increasing(const std::vector<double>& angles) {
  for (size_t i = 1; i < angles.size(); ++i)
    if (!(angles[i] > angles[i - 1])) return false;
  return true;
}

}  // namespace

double CandelaGrid::at(double gamma, double c) const {
  if (!(gamma >= vertical.front() && gamma <= vertical.back())) return 0.0;
  c = std::fmod(c, 360.0);
  if (c < 0) c += 360.0;
  const double folded = foldHorizontal(c, horizontal.front(), horizontal.back());
  const size_t nv = vertical.size();
  // Along the vertical angles in the two planes around `folded`, then between them.
  if (horizontal.size() == 1) return interpolate(vertical, gamma, candela.data(), 1);
  const size_t upper = std::min<size_t>(
      std::max<size_t>(size_t(std::upper_bound(horizontal.begin(), horizontal.end(), folded) - horizontal.begin()), 1),
      horizontal.size() - 1);
  const size_t lower = upper - 1;
  const double a = interpolate(vertical, gamma, candela.data() + lower * nv, 1);
  const double b = interpolate(vertical, gamma, candela.data() + upper * nv, 1);
  const double t = std::clamp((folded - horizontal[lower]) / (horizontal[upper] - horizontal[lower]), 0.0, 1.0);
  return a * (1.0 - t) + b * t;
}

std::string CandelaGrid::problem() const {
  if (vertical.size() < 2) return fmt::format("{} vertical angle(s); at least 2 are needed", vertical.size());
  if (horizontal.empty()) return "no horizontal angle";
  if (!increasing(vertical)) return "the vertical angles do not increase";
  if (!increasing(horizontal)) return "the horizontal angles do not increase";
  if (!(vertical.front() == 0.0 || vertical.front() == 90.0) || !(vertical.back() == 90.0 || vertical.back() == 180.0))
    return fmt::format("the vertical angles run {}-{}; type C runs from 0 or 90 to 90 or 180 degrees",
                       vertical.front(), vertical.back());
  const double first = horizontal.front(), last = horizontal.back();
  const bool known = (horizontal.size() == 1 && first == 0.0) ||
                     (first == 0.0 && (last == 90.0 || last == 180.0 || last == 360.0)) ||
                     (first == 90.0 && last == 270.0);
  if (!known)
    return fmt::format("the horizontal angles run {}-{}; type C runs 0, 0-90, 0-180, 90-270 or 0-360 degrees", first,
                       last);
  if (candela.size() != vertical.size() * horizontal.size())
    return fmt::format("{} candela values for {} x {} angles", candela.size(), horizontal.size(), vertical.size());
  for (size_t i = 0; i < candela.size(); ++i)
    if (!std::isfinite(candela[i]) || candela[i] < 0)
      return fmt::format("candela value {} ({}) is negative or not finite", i + 1, candela[i]);
  return {};
}

}  // namespace portico
