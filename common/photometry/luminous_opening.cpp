#include "common/photometry/luminous_opening.h"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <stdexcept>

namespace portico {

namespace {

// The ray's parameters within which a quantity linear in t stays in
// [-half, half] (origin o, rate d); false when it never does.
bool clipSlab(double o, double d, double half, double& enter, double& leave) {
  if (d == 0) return std::abs(o) <= half;
  double a = (-half - o) / d, b = (half - o) / d;
  if (a > b) std::swap(a, b);
  enter = std::max(enter, a);
  leave = std::min(leave, b);
  return enter <= leave;
}

// The same for |p + t dp|^2 <= 1 (a unit circle or sphere in scaled
// coordinates): a quadratic in t.
bool clipUnitBall(double pp, double pdp, double dpdp, double& enter, double& leave) {
  if (dpdp == 0) return pp <= 1;
  const double discriminant = pdp * pdp - dpdp * (pp - 1);
  if (discriminant < 0) return false;
  const double root = std::sqrt(discriminant);
  enter = std::max(enter, (-pdp - root) / dpdp);
  leave = std::min(leave, (-pdp + root) / dpdp);
  return enter <= leave;
}

}  // namespace

LuminousOpening LuminousOpening::fromLm63(double width, double length, double height) {
  LuminousOpening opening;
  opening.width_ = width, opening.length_ = length, opening.height_ = height;
  if (!std::isfinite(width) || !std::isfinite(length) || !std::isfinite(height))
    throw std::invalid_argument(fmt::format("the luminous opening (width {}, length {}, height {}) is not finite",
                                            width, length, height));
  const double w = std::abs(width), l = std::abs(length), h = std::abs(height);
  const auto sign = [](double v) { return v > 0 ? '+' : v < 0 ? '-' : '0'; };
  const std::string pattern{sign(width), sign(length), sign(height)};
  Shape shape = Shape::None;
  int axis = 2;
  Vec3 size;
  if (pattern == "000") {
    shape = Shape::None;
  } else if (width >= 0 && length >= 0 && height >= 0) {
    shape = Shape::Box, size = Vec3(float(l), float(w), float(h));
  } else if (pattern == "--0" || pattern == "--+") {
    shape = Shape::Cylinder, axis = 2, size = Vec3(float(l), float(w), float(h));
  } else if (pattern == "---") {
    shape = Shape::Ellipsoid, size = Vec3(float(l), float(w), float(h));
  } else if (pattern == "-+-" || pattern == "-0-") {
    shape = Shape::Cylinder, axis = 0, size = Vec3(float(l), float(w), float(h));
  } else if (pattern == "+--" || pattern == "0--") {
    shape = Shape::Cylinder, axis = 1, size = Vec3(float(l), float(w), float(h));
  } else if (pattern == "-00") {
    shape = Shape::Cylinder, axis = 2, size = Vec3(float(w), float(w), 0.0f);
  } else {
    throw std::invalid_argument(fmt::format(
        "the luminous opening (width {}, length {}, height {}) is none of LM-63's shapes (negative sizes mark round "
        "ones: -w -l 0 a circle or ellipse, -w -l h a vertical cylinder, -w -l -h a sphere or ellipsoid, -w l -h or "
        "w -l -h a horizontal cylinder)",
        width, length, height));
  }
  opening.shape_ = shape;
  opening.axis_ = axis;
  opening.size_ = size;
  const int nonzero = (size.x > 0) + (size.y > 0) + (size.z > 0);
  opening.visible_ = shape == Shape::Box ? nonzero >= 2 : shape != Shape::None;
  return opening;
}

std::string LuminousOpening::describe() const {
  const auto m = [](float v) { return fmt::format("{:g}", v); };
  const Vec3 s = size_;
  switch (shape_) {
    case Shape::None: return "none (a point: no camera sees it)";
    case Shape::Box:
      if (s.z == 0) return fmt::format("rectangle {} x {} m (length x width)", m(s.x), m(s.y));
      return fmt::format("box {} x {} x {} m (length x width x height)", m(s.x), m(s.y), m(s.z));
    case Shape::Ellipsoid:
      if (s.x == s.y && s.y == s.z) return fmt::format("sphere {} m", m(s.x));
      return fmt::format("ellipsoid {} x {} x {} m", m(s.x), m(s.y), m(s.z));
    case Shape::Cylinder: {
      static const char* const kAxes[] = {"C0", "C90", "the nadir"};
      const int i = (axis_ + 1) % 3, j = (axis_ + 2) % 3;
      const std::string across = s[i] == s[j] ? fmt::format("diameter {} m", m(s[i]))
                                              : fmt::format("{} x {} m across", m(s[i]), m(s[j]));
      if (s[axis_] == 0) return fmt::format("{} {} facing along {}", s[i] == s[j] ? "circle" : "ellipse", across,
                                             kAxes[axis_]);
      return fmt::format("cylinder {} long along {}, {}", m(s[axis_]), kAxes[axis_], across);
    }
  }
  return "";
}

double LuminousOpening::projectedArea(const Vec3& local) const {
  const double x = local.x, y = local.y, z = local.z;
  const double sx = size_.x, sy = size_.y, sz = size_.z;
  switch (shape_) {
    case Shape::None: return 0;
    case Shape::Box: return std::abs(x) * sy * sz + std::abs(y) * sx * sz + std::abs(z) * sx * sy;
    case Shape::Ellipsoid: {
      const double a = sx / 2, b = sy / 2, c = sz / 2;
      return kPi * std::sqrt(b * b * c * c * x * x + a * a * c * c * y * y + a * a * b * b * z * z);
    }
    case Shape::Cylinder: {
      // Its end (the ellipse, seen at an angle) plus its side: the length
      // times the ellipse's width across the direction's part in its plane.
      const int i = (axis_ + 1) % 3, j = (axis_ + 2) % 3;
      const double a = size_[i] / 2.0, b = size_[j] / 2.0, h = size_[axis_];
      const double wi = local[i], wj = local[j], wk = local[axis_];
      return std::abs(wk) * kPi * a * b + h * 2 * std::sqrt(a * a * wj * wj + b * b * wi * wi);
    }
  }
  return 0;
}

std::optional<float> LuminousOpening::hit(const Vec3& origin, const Vec3& direction, float tMin, float tMax) const {
  // Edge-on to a flat opening: no area to see (nor a luminance to show).
  if (!visible_ || !(projectedArea(direction) > 0)) return std::nullopt;
  double enter = -std::numeric_limits<double>::infinity(), leave = std::numeric_limits<double>::infinity();
  bool meets = true;
  switch (shape_) {
    case Shape::None: return std::nullopt;
    case Shape::Box:
      for (int k = 0; k < 3 && meets; ++k) meets = clipSlab(origin[k], direction[k], size_[k] / 2.0, enter, leave);
      break;
    case Shape::Ellipsoid: {
      double pp = 0, pdp = 0, dpdp = 0;
      for (int k = 0; k < 3; ++k) {
        const double p = origin[k] / (size_[k] / 2.0), dp = direction[k] / (size_[k] / 2.0);
        pp += p * p, pdp += p * dp, dpdp += dp * dp;
      }
      meets = clipUnitBall(pp, pdp, dpdp, enter, leave);
      break;
    }
    case Shape::Cylinder: {
      meets = clipSlab(origin[axis_], direction[axis_], size_[axis_] / 2.0, enter, leave);
      double pp = 0, pdp = 0, dpdp = 0;
      for (const int k : {(axis_ + 1) % 3, (axis_ + 2) % 3}) {
        const double p = origin[k] / (size_[k] / 2.0), dp = direction[k] / (size_[k] / 2.0);
        pp += p * p, pdp += p * dp, dpdp += dp * dp;
      }
      meets = meets && clipUnitBall(pp, pdp, dpdp, enter, leave);
      break;
    }
  }
  // From inside (a camera in the luminaire) it is not seen.
  if (!meets || !(enter > double(tMin)) || !(enter < double(tMax))) return std::nullopt;
  return static_cast<float>(enter);
}

}  // namespace portico
