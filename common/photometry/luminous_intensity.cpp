#include "common/photometry/luminous_intensity.h"

#include <algorithm>
#include <cmath>

namespace portico {

namespace {
constexpr double kDegree = M_PI / 180.0;
constexpr double kRowDegrees = 180.0 / LuminousIntensity::kVerticalCells;

// The entry of a running sum `cdf` (n + 1 entries from 0) whose span holds
// target, skipping empty spans; -1 if every span is empty.
int findSpan(const double* cdf, int n, double target) {
  if (!(cdf[n] > 0)) return -1;
  int span = int(std::upper_bound(cdf + 1, cdf + n + 1, target) - (cdf + 1));
  span = std::min(span, n - 1);
  while (span > 0 && !(cdf[span + 1] > cdf[span])) --span;   // target at the very top: the last nonempty span
  while (span < n - 1 && !(cdf[span + 1] > cdf[span])) ++span;
  return span;
}
}  // namespace

LuminousIntensity::LuminousIntensity(CandelaGrid grid, std::string name)
    : grid_(std::move(grid)), name_(std::move(name)), horizontalCells_(grid_.horizontal.size() == 1 ? 1 : kHorizontalCells) {
  const int rows = kVerticalCells, columns = horizontalCells_;
  const double columnDegrees = 360.0 / columns;
  cells_.resize(size_t(rows) * columns);
  cosBoundary_.resize(rows + 1);
  for (int row = 0; row <= rows; ++row) cosBoundary_[row] = std::cos(row * kRowDegrees * kDegree);
  rowCdf_.assign(rows + 1, 0.0);
  columnCdf_.assign(size_t(rows) * (columns + 1), 0.0);
  for (int row = 0; row < rows; ++row) {
    const double gamma = (row + 0.5) * kRowDegrees;
    const double solidAngle = (cosBoundary_[row] - cosBoundary_[row + 1]) * (2.0 * M_PI / columns);
    double* cdf = &columnCdf_[size_t(row) * (columns + 1)];
    for (int column = 0; column < columns; ++column) {
      const float value = static_cast<float>(grid_.at(gamma, (column + 0.5) * columnDegrees));
      cells_[size_t(row) * columns + column] = value;
      cdf[column + 1] = cdf[column] + double(value) * solidAngle;
    }
    rowCdf_[row + 1] = rowCdf_[row] + cdf[columns];
  }
  lumens_ = rowCdf_[rows];
}

float LuminousIntensity::candela(const Vec3& local) const {
  const double gamma = std::acos(std::clamp(double(local.z), -1.0, 1.0)) / kDegree;
  const int row = std::min(int(gamma / kRowDegrees), kVerticalCells - 1);
  int column = 0;
  if (horizontalCells_ > 1) {
    double c = std::atan2(double(local.y), double(local.x)) / kDegree;
    if (c < 0) c += 360.0;
    column = std::min(int(c / (360.0 / horizontalCells_)), horizontalCells_ - 1);
  }
  return cells_[size_t(row) * horizontalCells_ + column];
}

Vec3 LuminousIntensity::sample(float cellU, float cellV, float withinU, float withinV) const {
  const int row = findSpan(rowCdf_.data(), kVerticalCells, double(cellU) * lumens_);
  if (row < 0) return Vec3(0, 0, 1);
  const double* cdf = &columnCdf_[size_t(row) * (horizontalCells_ + 1)];
  const int column = findSpan(cdf, horizontalCells_, double(cellV) * cdf[horizontalCells_]);
  // Uniform in solid angle over the cell: cos(gamma) uniform between its bounds.
  const double cosGamma = cosBoundary_[row] + (cosBoundary_[row + 1] - cosBoundary_[row]) * double(withinU);
  const double sinGamma = std::sqrt(std::max(0.0, 1.0 - cosGamma * cosGamma));
  const double c = (column + double(withinV)) * (2.0 * M_PI / horizontalCells_);
  return Vec3(float(sinGamma * std::cos(c)), float(sinGamma * std::sin(c)), float(cosGamma));
}

}  // namespace portico
