#include "common/photometry/lamp_colour.h"

#include <gtest/gtest.h>

#include "common/analysis/sensor.h"

namespace portico {
namespace {

// Published chromaticities of the Planckian locus (CIE 15:2004 and
// Wyszecki & Stiles, computed from the CIE 1931 colour-matching functions):
// Kang et al.'s fits are within 1e-3 of them.
TEST(LampColour, PlanckianChromaticityFollowsTheLocus) {
  struct Point {
    double kelvin, x, y;
  };
  for (const Point& p : {Point{2000, 0.5267, 0.4133}, Point{2856, 0.4476, 0.4074}, Point{4000, 0.3805, 0.3768},
                         Point{6500, 0.3135, 0.3237}, Point{10000, 0.2807, 0.2884}}) {
    const Chromaticity c = planckianChromaticity(p.kelvin);
    EXPECT_NEAR(c.x, p.x, 1e-3) << p.kelvin << " K";
    EXPECT_NEAR(c.y, p.y, 1e-3) << p.kelvin << " K";
  }
}

TEST(LampColour, ColourTemperaturesGiveUnitLuminanceWarmToCool) {
  const Vec3 warm = colourOfTemperature(2700), neutral = colourOfTemperature(4000), cool = colourOfTemperature(6500);
  for (const Vec3& c : {warm, neutral, cool}) EXPECT_NEAR(rec709Y(c), 1.0, 1e-6);
  EXPECT_GT(warm.x / warm.z, neutral.x / neutral.z);
  EXPECT_GT(neutral.x / neutral.z, cool.x / cool.z);
  // 6500 K is near D65, Rec. 709's white: nearly equal channels.
  EXPECT_NEAR(cool.x / cool.z, 1.0, 0.1);
  EXPECT_EQ(colourTemperatureProblem(1000), "colour temperature 1000 K lies outside 1667-25000 K");
  EXPECT_EQ(colourTemperatureProblem(3000), "");
}

TEST(LampColour, LumensBecomePowerAndRadianceThatGiveThemBack) {
  const Vec3 colour(12, 11, 9.5);
  const Vec3 power = powerOfLumens(1000, colour);
  EXPECT_NEAR(lumensOfPower(power), 1000, 1e-3);
  EXPECT_NEAR(power.x / power.z, 12 / 9.5, 1e-6);
  // A 0.6 x 0.6 m panel: Phi = pi A L per channel.
  const Vec3 radiance = radianceOfLumens(3600, colour, 0.36);
  EXPECT_NEAR(lumensOfPower(radiance * float(M_PI * 0.36)), 3600, 1e-2);
}

}  // namespace
}  // namespace portico
