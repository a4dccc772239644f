// The sun's position against published values (NREL's Solar Position
// Algorithm, Reda & Andreas 2004, NREL/TP-560-34302: its worked example)
// and against what the geometry of the seasons requires: the equinox's noon
// sun at 90 - |latitude|, the June solstice's at 90 - latitude + 23.44,
// the southern winter sun due north, the polar night's sun under the
// horizon all day and the midnight sun above it.
#include "common/transport/solar_position.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace portico {
namespace {

// The obliquity of the ecliptic in 2026 (IAU 2006: 23.4393 - 0.0130 T).
constexpr double kObliquity2026 = 23.4360;
constexpr int64_t kMinute = 60, kDay = 86400;

// The highest the sun stands over the UTC day starting at `dayStart`,
// searched minute by minute, with its azimuth then.
SolarPosition highestOfDay(int64_t dayStart, double latitude, double longitude) {
  SolarPosition best{0, -91};
  for (int64_t t = dayStart; t < dayStart + kDay; t += kMinute) {
    const SolarPosition sun = solarPosition(t, latitude, longitude);
    if (sun.elevationDegrees > best.elevationDegrees) best = sun;
  }
  return best;
}

double angleBetweenAzimuths(double a, double b) {
  const double d = std::fmod(std::fabs(a - b), 360.0);
  return std::min(d, 360.0 - d);
}

// NREL SPA's example: 2003-10-17 12:30:30 at UTC-7, Golden, Colorado
// (39.742476 N, 105.1786 W): topocentric elevation without refraction
// 39.872046, azimuth 194.340241 (from north, eastward); and the next day,
// 39.505196 and 194.311132 (as pvlib's tests of SPA list them).
TEST(SolarPosition, MatchesNrelSpasWorkedExampleWithinAHundredthOfADegree) {
  const int64_t example = 1066419030;   // 2003-10-17T19:30:30Z
  SolarPosition sun = solarPosition(example, 39.742476, -105.1786);
  EXPECT_NEAR(sun.elevationDegrees, 39.872046, 0.01);
  EXPECT_NEAR(sun.azimuthDegrees, 194.340241, 0.01);
  sun = solarPosition(example + kDay, 39.742476, -105.1786);
  EXPECT_NEAR(sun.elevationDegrees, 39.505196, 0.01);
  EXPECT_NEAR(sun.azimuthDegrees, 194.311132, 0.01);
}

// The March 2026 equinox is at 14:46 UTC; at 40 W the sun culminates then.
TEST(SolarPosition, EquinoxNoonSunStandsAtNinetyMinusTheLatitude) {
  const int64_t march20 = 1773964800;   // 2026-03-20T00:00Z
  for (const double latitude : {49.1003, 0.0, -33.8688, 65.0}) {
    const SolarPosition noon = highestOfDay(march20, latitude, -40.0);
    // At the equator the sun passes the zenith at 0.25 degrees a minute:
    // the minute steps miss its top by up to about 0.1 degrees there.
    EXPECT_NEAR(noon.elevationDegrees, 90.0 - std::fabs(latitude), latitude == 0.0 ? 0.15 : 0.05)
        << "latitude " << latitude;
  }
}

TEST(SolarPosition, JuneSolsticeNoonSunIsTheObliquityAboveTheEquinoxsNorthAndBelowItSouth) {
  const int64_t june21 = 1782000000;   // 2026-06-21T00:00Z
  const SolarPosition karlsruhe = highestOfDay(june21, 49.1003, 8.4366);
  EXPECT_NEAR(karlsruhe.elevationDegrees, 90.0 - 49.1003 + kObliquity2026, 0.05);
  EXPECT_LT(angleBetweenAzimuths(karlsruhe.azimuthDegrees, 180.0), 1.0);   // due south at noon
  // Southern winter: low, and due north.
  const SolarPosition sydney = highestOfDay(june21, -33.8688, 151.2093);
  EXPECT_NEAR(sydney.elevationDegrees, 90.0 - 33.8688 - kObliquity2026, 0.05);
  EXPECT_LT(angleBetweenAzimuths(sydney.azimuthDegrees, 0.0), 1.0);
}

TEST(SolarPosition, EquinoxSunRisesInTheEastAndSetsInTheWest) {
  const int64_t march20 = 1773964800;
  bool rose = false, set = false;
  SolarPosition previous = solarPosition(march20, 49.1003, 8.4366);
  for (int64_t t = march20 + kMinute; t < march20 + kDay; t += kMinute) {
    const SolarPosition sun = solarPosition(t, 49.1003, 8.4366);
    if (previous.elevationDegrees <= 0 && sun.elevationDegrees > 0) {
      EXPECT_NEAR(sun.azimuthDegrees, 90.0, 1.0);
      rose = true;
    }
    if (previous.elevationDegrees > 0 && sun.elevationDegrees <= 0) {
      EXPECT_NEAR(sun.azimuthDegrees, 270.0, 1.0);
      set = true;
    }
    previous = sun;
  }
  EXPECT_TRUE(rose);
  EXPECT_TRUE(set);
}

// Tromsø, 69.65 N: polar night at the December solstice (the noon sun some
// 3 degrees down), the midnight sun at the June one.
TEST(SolarPosition, PolarNightKeepsTheSunUnderTheHorizonAllDay) {
  const int64_t december21 = 1797811200;   // 2026-12-21T00:00Z
  const SolarPosition noon = highestOfDay(december21, 69.6492, 18.9553);
  EXPECT_LT(noon.elevationDegrees, 0.0);
  EXPECT_NEAR(noon.elevationDegrees, 90.0 - 69.6492 - kObliquity2026, 0.05);
  const int64_t june20Midnight = 1782000000 - 75 * kMinute;   // 22:45Z: local solar midnight, about
  EXPECT_GT(solarPosition(june20Midnight, 69.6492, 18.9553).elevationDegrees, 2.0);
}

TEST(SolarPosition, RefusesAPlaceOffTheEarthAndAYearOutsideItsFit) {
  EXPECT_THROW(solarPosition(0, 95, 0), std::invalid_argument);
  EXPECT_THROW(solarPosition(0, 45, -181), std::invalid_argument);
  EXPECT_THROW(solarPosition(0, std::nan(""), 0), std::invalid_argument);
  try {
    solarPosition(-6000000000, 45, 0);   // 1779-11-13
    FAIL() << "1779 was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("1779"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(solarPosition(0, -90, 180));
}

}  // namespace
}  // namespace portico
