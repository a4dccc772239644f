// A luminaire's luminous opening (IES LM-63-2002, section on the luminous
// opening's width, length and height): the part of the luminaire that
// glows, as a camera sees it. Its luminance towards a direction is the
// luminaire's intensity that way over the opening's area projected on a
// plane across it: L = I / A_projected (cd/m^2), so a camera sees the
// luminaire as bright as it is in each direction.
//
// Sizes are in the luminaire's frame (luminous_intensity.h): x along C0
// (the file's "length", along the 0-180 degree plane), y along C90 (its
// "width", along the 90-270 degree plane), z along the nadir (its
// "height"). The shape is centred on the luminaire's photometric centre.
// LM-63 gives round shapes by negative sizes:
//
//   width length height   shape (read here as)
//     0     0      0      a point: no opening, no camera sees it
//     w     l      h      a box l x w x h (h 0: a flat rectangle)
//    -w    -l      h      an elliptic cylinder along z (h 0: a flat ellipse or circle)
//    -w    -l     -h      an ellipsoid (a sphere when all are equal)
//    -w     l     -h      a cylinder along x (C0), length l
//     w    -l     -h      a cylinder along y (C90), length w
//    -w     0     -h      a vertical ellipse facing C0 (a cylinder along x of length 0)
//     0    -l     -h      a vertical ellipse facing C90 (along y, length 0)
//    -d     0      0      a circle of diameter d (LM-63-1995's way of writing it)
//
// Any other sign pattern is refused (fromLm63's message).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "common/math.h"

namespace portico {

class LuminousOpening {
 public:
  enum class Shape : uint8_t { None, Box, Cylinder, Ellipsoid };

  LuminousOpening() = default;
  // From LM-63's width, length and height (metres, signs as above); throws
  // std::invalid_argument naming the pattern when it is none of the above.
  static LuminousOpening fromLm63(double width, double length, double height);

  // As given (metres, LM-63 signs): what the store keeps.
  double width() const { return width_; }
  double length() const { return length_; }
  double height() const { return height_; }
  Shape shape() const { return shape_; }
  // Whether a camera can see it: a shape whose projection has an area in
  // some direction (a point, or a box thin in two axes, has none).
  bool visible() const { return visible_; }
  // Extents along x, y, z of the luminaire's frame (full sizes, metres).
  Vec3 size() const { return size_; }
  // "rectangle 0.6 x 0.6 m", "sphere 0.3 m", "none (a point)".
  std::string describe() const;

  // Its area projected on a plane across unit direction `local` (m^2).
  double projectedArea(const Vec3& local) const;
  // The nearest t in (tMin, tMax) at which the ray origin + t direction
  // (the luminaire's frame, centred on its photometric centre) meets it;
  // none when it misses or the opening is not visible.
  std::optional<float> hit(const Vec3& origin, const Vec3& direction, float tMin, float tMax) const;

 private:
  double width_ = 0, length_ = 0, height_ = 0;
  Shape shape_ = Shape::None;
  int axis_ = 2;   // a cylinder's axis (0 x, 1 y, 2 z)
  Vec3 size_;
  bool visible_ = false;
};

}  // namespace portico
