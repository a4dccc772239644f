// A luminaire's luminous opening: LM-63's width, length and height read as
// its table of shapes says, and each shape's projected area (the divisor of
// its luminance) against the area a grid of parallel rays meets with hit().
#include "common/photometry/luminous_opening.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "common/photometry/ies_file.h"
#include "tests/unit/photometry/ies_test_files.h"

namespace portico {
namespace {

TEST(LuminousOpening, ReadsEveryShapeOfTheLm63Table) {
  using Shape = LuminousOpening::Shape;
  struct Case {
    double width, length, height;
    Shape shape;
    Vec3 size;   // length (C0), width (C90), height (nadir)
    const char* described;
  };
  const Case cases[] = {
      {0, 0, 0, Shape::None, Vec3(0), "none (a point: no camera sees it)"},
      {0.3, 0.6, 0, Shape::Box, Vec3(0.6f, 0.3f, 0), "rectangle 0.6 x 0.3 m (length x width)"},
      {0.3, 0.6, 0.1, Shape::Box, Vec3(0.6f, 0.3f, 0.1f), "box 0.6 x 0.3 x 0.1 m (length x width x height)"},
      {-0.2, -0.2, 0, Shape::Cylinder, Vec3(0.2f, 0.2f, 0), "circle diameter 0.2 m facing along the nadir"},
      {-0.2, -0.4, 0, Shape::Cylinder, Vec3(0.4f, 0.2f, 0), "ellipse 0.4 x 0.2 m across facing along the nadir"},
      {-0.2, -0.2, 0.3, Shape::Cylinder, Vec3(0.2f, 0.2f, 0.3f), "cylinder 0.3 long along the nadir, diameter 0.2 m"},
      {-0.3, -0.3, -0.3, Shape::Ellipsoid, Vec3(0.3f), "sphere 0.3 m"},
      {-0.1, 1.2, -0.1, Shape::Cylinder, Vec3(1.2f, 0.1f, 0.1f), "cylinder 1.2 long along C0, diameter 0.1 m"},
      {1.2, -0.1, -0.1, Shape::Cylinder, Vec3(0.1f, 1.2f, 0.1f), "cylinder 1.2 long along C90, diameter 0.1 m"},
      {-0.2, 0, -0.2, Shape::Cylinder, Vec3(0, 0.2f, 0.2f), "circle diameter 0.2 m facing along C0"},
      {-0.25, 0, 0, Shape::Cylinder, Vec3(0.25f, 0.25f, 0), "circle diameter 0.25 m facing along the nadir"},
  };
  for (const Case& c : cases) {
    const LuminousOpening opening = LuminousOpening::fromLm63(c.width, c.length, c.height);
    EXPECT_EQ(opening.shape(), c.shape) << c.described;
    EXPECT_EQ(opening.size(), c.size) << c.described;
    EXPECT_EQ(opening.describe(), c.described);
    EXPECT_EQ(opening.visible(), c.shape != Shape::None);
  }
  // A box thin in two axes has no area to see.
  EXPECT_FALSE(LuminousOpening::fromLm63(0.5, 0, 0).visible());
  // Sign patterns LM-63 gives no shape.
  for (const Vec3& bad : {Vec3(-0.2f, 0.3f, 0), Vec3(0.2f, -0.3f, 0.1f), Vec3(0, 0, -0.1f), Vec3(0, -0.2f, 0)})
    EXPECT_THROW(LuminousOpening::fromLm63(bad.x, bad.y, bad.z), std::invalid_argument) << bad.x << " " << bad.y << " " << bad.z;
}

TEST(LuminousOpening, AFileWithAnOpeningOfNoShapeIsRefusedNamingItsLine) {
  const std::string text = ies_test::iesText({0, 90}, {0}, [](double, double) { return 100.0; }, 1.0, 1.0,
                                             "IESNA:LM-63-2002", 1.0, "-0.2 0.3 0");
  try {
    parseIes(text, "odd.ies");
    FAIL() << "an opening of no shape was read";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("odd.ies: line 5: the luminous opening (width -0.2, length 0.3, height 0)"),
              std::string::npos)
        << e.what();
  }
  // Feet are read as feet: a 2 x 1 ft rectangle.
  std::string feet = ies_test::iesText({0, 90}, {0}, [](double, double) { return 100.0; }, 1.0, 1.0,
                                       "IESNA:LM-63-2002", 1.0, "1 2 0");
  feet.replace(feet.find(" 1 2 1 2 0\n"), 11, " 1 1 1 2 0\n");   // units 2 (metres) -> 1 (feet)
  const IesPhotometry read = parseIes(feet, "feet.ies");
  EXPECT_EQ(read.opening.shape(), LuminousOpening::Shape::Box);
  EXPECT_NEAR(read.opening.size().x, 2 * 0.3048, 1e-6);
  EXPECT_NEAR(read.opening.size().y, 0.3048, 1e-6);
}

// Parallel rays on a fine grid across a direction: the area of the cells
// whose ray meets the opening is its projected area that way.
double areaMetByRays(const LuminousOpening& opening, const Vec3& direction, int n) {
  Vec3 u, v;
  orthonormalBasis(direction, u, v);
  const double reach = 0.5 * length(opening.size()) * 1.01;
  const double step = 2 * reach / n;
  int met = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double a = -reach + (i + 0.5) * step, b = -reach + (j + 0.5) * step;
      const Vec3 origin = u * float(a) + v * float(b) - direction * 5.0f;
      met += opening.hit(origin, direction, 0.0f, kInfinity).has_value();
    }
  return met * step * step;
}

TEST(LuminousOpening, ProjectedAreaIsTheAreaParallelRaysMeet) {
  const Vec3 shapes[] = {{0.3f, 0.6f, 0},      {0.3f, 0.6f, 0.1f},     {-0.2f, -0.2f, 0}, {-0.2f, -0.4f, 0},
                         {-0.2f, -0.3f, 0.3f}, {-0.3f, -0.3f, -0.3f},  {-0.2f, -0.4f, -0.3f},
                         {-0.1f, 1.2f, -0.15f}, {1.2f, -0.1f, -0.15f}, {-0.2f, 0, -0.3f}, {0, -0.2f, -0.3f}};
  std::mt19937 random(7);
  std::normal_distribution<float> normal;
  for (const Vec3& given : shapes) {
    const LuminousOpening opening = LuminousOpening::fromLm63(given.x, given.y, given.z);
    for (int k = 0; k < 10; ++k) {
      const Vec3 direction = normalize(Vec3(normal(random), normal(random), normal(random)));
      const double expected = opening.projectedArea(direction);
      const double met = areaMetByRays(opening, direction, 300);
      EXPECT_NEAR(met, expected, 0.01 * expected + 2e-4)
          << opening.describe() << " towards " << direction.x << " " << direction.y << " " << direction.z;
    }
  }
  // Closed forms: a rectangle is L W |cos gamma|, a sphere pi r^2 every way.
  const Vec3 oblique = normalize(Vec3(0.3f, -0.4f, 0.8f));
  EXPECT_NEAR(LuminousOpening::fromLm63(0.3, 0.6, 0).projectedArea(oblique), 0.18 * 0.8 / length(Vec3(0.3f, -0.4f, 0.8f)),
              1e-6);
  EXPECT_NEAR(LuminousOpening::fromLm63(-0.3, -0.3, -0.3).projectedArea(oblique), M_PI * 0.15 * 0.15, 1e-6);
  // A vertical cylinder: its disc |cos gamma| pi r^2 plus its side D H sin gamma.
  const double cosGamma = 0.8 / length(Vec3(0.3f, -0.4f, 0.8f)), sinGamma = std::sqrt(1 - cosGamma * cosGamma);
  EXPECT_NEAR(LuminousOpening::fromLm63(-0.2, -0.2, 0.3).projectedArea(oblique),
              cosGamma * M_PI * 0.01 + sinGamma * 0.2 * 0.3, 1e-6);
}

TEST(LuminousOpening, ARayMeetsItOnceFromOutsideAndNeverEdgeOnOrFromInside) {
  const LuminousOpening panel = LuminousOpening::fromLm63(0.6, 0.6, 0);
  // Straight up from 2 m under it: met at 2 m; not met beyond tMax, nor from above in the other way.
  const std::optional<float> t = panel.hit(Vec3(0.1f, 0.1f, 2), Vec3(0, 0, -1), 0, kInfinity);
  ASSERT_TRUE(t.has_value());
  EXPECT_FLOAT_EQ(*t, 2.0f);
  EXPECT_FALSE(panel.hit(Vec3(0.1f, 0.1f, 2), Vec3(0, 0, -1), 0, 1.9f).has_value());
  EXPECT_FALSE(panel.hit(Vec3(0.1f, 0.1f, 2), Vec3(0, 0, 1), 0, kInfinity).has_value());
  // Edge-on: in its plane, it has no area.
  EXPECT_FALSE(panel.hit(Vec3(-2, 0, 0), Vec3(1, 0, 0), 0, kInfinity).has_value());
  // Beside it.
  EXPECT_FALSE(panel.hit(Vec3(0.31f, 0, 2), Vec3(0, 0, -1), 0, kInfinity).has_value());
  // From inside a sphere, nothing is seen.
  EXPECT_FALSE(LuminousOpening::fromLm63(-0.3, -0.3, -0.3).hit(Vec3(0), Vec3(1, 0, 0), 0, kInfinity).has_value());
  // A point: never.
  EXPECT_FALSE(LuminousOpening().hit(Vec3(0, 0, 2), Vec3(0, 0, -1), 0, kInfinity).has_value());
}

}  // namespace
}  // namespace portico
