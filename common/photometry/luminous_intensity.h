// A luminaire's luminous intensity over the whole sphere, as portico uses
// it: the candela grid of its photometric file (candela_grid.h) read at the
// middle of fine cells, 0.5 degree of vertical angle by 1 degree of
// horizontal angle (one cell around for a file of one horizontal plane),
// and constant over each cell. Emitted photons, direct light and the
// luminaire's total lumens all read this one function, so photons carry
// exactly the luminaire's flux and the intensity they are drawn from is the
// one shadow rays see.
//
// Directions are in the luminaire's frame: x along its C0 direction, y
// along C90, z along the nadir (vertical angle 0).
#pragma once

#include <string>
#include <vector>

#include "common/math.h"
#include "common/photometry/candela_grid.h"

namespace portico {

class LuminousIntensity {
 public:
  static constexpr int kVerticalCells = 360;     // 0.5 degree each
  static constexpr int kHorizontalCells = 360;   // 1 degree each

  // `name`: where it came from (the photometric file's name), for messages.
  // The grid must be valid (CandelaGrid::problem() empty).
  LuminousIntensity(CandelaGrid grid, std::string name);

  const CandelaGrid& grid() const { return grid_; }
  const std::string& name() const { return name_; }
  // Candela towards unit direction `local` (the luminaire's frame).
  float candela(const Vec3& local) const;
  // The luminous flux: the sum over the cells of candela x solid angle (lm).
  double lumens() const { return lumens_; }
  // A unit direction (the luminaire's frame) drawn with probability density
  // candela / lumens per steradian, from four uniform numbers in [0, 1): a
  // cell by the first two, a uniform direction within it by the others.
  Vec3 sample(float cellU, float cellV, float withinU, float withinV) const;

 private:
  CandelaGrid grid_;
  std::string name_;
  int horizontalCells_;
  std::vector<float> cells_;          // vertical-major: cells_[row * horizontalCells_ + column]
  std::vector<double> rowCdf_;        // running flux over rows, kVerticalCells + 1 entries
  std::vector<double> columnCdf_;     // per row, running flux over its columns (horizontalCells_ + 1 entries)
  std::vector<double> cosBoundary_;   // cos of the vertical angle at each row boundary
  double lumens_ = 0;
};

}  // namespace portico
