// `--sun-time`: ISO 8601 instants with their offsets, the geographic
// azimuth turned into portico's (east where a camera looking north has its
// right), and the sun resolved from the job's place or the store's site.
#include "common/job/sun_time.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "common/transport/camera_model.h"
#include "common/transport/sky_model.h"
#include "common/transport/solar_position.h"

namespace portico {
namespace {

std::string parseError(const std::string& text) {
  try {
    parseIsoInstant(text);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(SunTime, ReadsAnInstantWithItsUtcOffset) {
  const int64_t noonUtc = 1782045000;   // 2026-06-21T12:30:00Z
  EXPECT_EQ(parseIsoInstant("2026-06-21T12:30Z"), noonUtc);
  EXPECT_EQ(parseIsoInstant("2026-06-21T12:30:00Z"), noonUtc);
  EXPECT_EQ(parseIsoInstant("2026-06-21T14:30+02:00"), noonUtc);
  EXPECT_EQ(parseIsoInstant("2026-06-21 14:30+0200"), noonUtc);
  EXPECT_EQ(parseIsoInstant("2026-06-21T09:30-03"), noonUtc);
  EXPECT_EQ(parseIsoInstant("2024-02-29T23:59:59+05:30"), 1709231399);   // a leap day, a half-hour zone
  EXPECT_EQ(parseIsoInstant("1969-07-20T20:17:40Z"), -14182940);
  EXPECT_EQ(formatUtcInstant(noonUtc), "2026-06-21T12:30:00Z");
  EXPECT_EQ(formatUtcInstant(-14182940), "1969-07-20T20:17:40Z");
}

TEST(SunTime, RefusesATimeWithoutAnOffsetAndDatesThatDoNotExist) {
  EXPECT_NE(parseError("2026-06-21T14:30").find("'2026-06-21T14:30' has no UTC offset"), std::string::npos)
      << parseError("2026-06-21T14:30");
  EXPECT_NE(parseError("2026-02-29T12:00Z").find("2026-02 has no day 29"), std::string::npos);
  EXPECT_NE(parseError("2026-06-21T24:00Z").find("no time of day"), std::string::npos);
  EXPECT_NE(parseError("2026-06-21T12:00+25:00").find("no valid UTC offset"), std::string::npos);
  EXPECT_NE(parseError("21/06/2026 12:00Z").find("is not a date and time"), std::string::npos);
  EXPECT_NE(parseError("").find("is not a date and time"), std::string::npos);
  for (const char* text : {"2026-06-21T14:30", "2026-13-01T00:00Z", "noon"})
    EXPECT_EQ(parseError(text).find('\n'), std::string::npos) << text;
}

// portico is right-handed with +Y up: a camera looking north has east on
// its right, as a person facing north has. So with north at +Z (north
// azimuth 0) east is -X, portico azimuth 270, and in general geographic
// azimuth A is portico azimuth north - A.
TEST(SunTime, EastIsWhereACameraLookingNorthHasItsRight) {
  EXPECT_DOUBLE_EQ(porticoAzimuth(0, 90), 270);
  const Vec3 east = sunDirection(float(porticoAzimuth(0, 90)), 0);
  EXPECT_NEAR(east.x, -1, 1e-6);
  EXPECT_NEAR(east.z, 0, 1e-6);
  for (const double north : {0.0, 30.0, 90.0, 180.0, -135.0, 300.0}) {
    Camera camera;
    camera.origin = Vec3(0, 0, 0);
    camera.target = sunDirection(float(north), 0);   // looking north
    camera.up = Vec3(0, 1, 0);
    const CameraModel model(camera, 64, 64);
    // The image's edges, 30 degrees either side of north (60 degree fov).
    const Vec3 right = model.direction(64, 32), left = model.direction(0, 32);
    const Vec3 towardsEast = sunDirection(float(porticoAzimuth(north, 90)), 0);
    const Vec3 towardsWest = sunDirection(float(porticoAzimuth(north, 270)), 0);
    EXPECT_GT(dot(right, towardsEast), 0.45f) << "north at " << north;
    EXPECT_LT(dot(left, towardsEast), -0.45f) << "north at " << north;
    EXPECT_GT(dot(left, towardsWest), 0.45f) << "north at " << north;
    // Geographic north itself, and south opposite it.
    EXPECT_NEAR(porticoAzimuth(north, 0), std::fmod(north + 360, 360), 1e-9);
    EXPECT_NEAR(dot(sunDirection(float(porticoAzimuth(north, 180)), 0), camera.target), -1, 1e-5);
  }
}

DaylightSettings atTime(const std::string& when) {
  DaylightSettings d;
  d.sky = DaylightSettings::Sky::Preetham;
  d.sun = true;
  d.sunTime = SunTime{parseIsoInstant(when), std::nullopt, std::nullopt, std::nullopt};
  return d;
}

std::string resolveError(const DaylightSettings& d, const std::optional<SiteLocation>& site) {
  try {
    resolveSunTime(d, site, "/stores/house");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(SunTime, ResolvesToTheAnglesOfSunAtTheStoresSiteOrTheJobsPlace) {
  const SiteLocation karlsruhe{49.1003, 8.4366, 20.0};
  const DaylightSettings asked = atTime("2026-06-21T14:30+02:00");
  const DaylightSettings resolved = resolveSunTime(asked, karlsruhe, "/stores/house");
  const SolarPosition sun = solarPosition(1782045000, 49.1003, 8.4366);
  EXPECT_FALSE(resolved.sunTime);
  EXPECT_TRUE(resolved.sun);
  EXPECT_EQ(resolved.sunElevationDegrees, float(sun.elevationDegrees));
  EXPECT_EQ(resolved.sunAzimuthDegrees, float(porticoAzimuth(20.0, sun.azimuthDegrees)));
  EXPECT_EQ(daylightProblem(resolved), "");
  // Resolving again changes nothing.
  EXPECT_EQ(resolveSunTime(resolved, karlsruhe, "/stores/house"), resolved);

  // The job's place and north override the site's: at 02:00Z it is night
  // in Karlsruhe and noon in Sydney, whose winter sun stands in the north.
  DaylightSettings own = atTime("2026-06-21T02:00Z");
  EXPECT_NE(resolveError(own, karlsruhe).find("below the horizon"), std::string::npos);
  own.sunTime->latitudeDegrees = -33.8688;
  own.sunTime->longitudeDegrees = 151.2093;
  own.sunTime->northAzimuthDegrees = 0.0;
  const DaylightSettings sydney = resolveSunTime(own, karlsruhe, "/stores/house");
  const SolarPosition there = solarPosition(1782007200, -33.8688, 151.2093);
  EXPECT_EQ(sydney.sunElevationDegrees, float(there.elevationDegrees));
  EXPECT_EQ(sydney.sunAzimuthDegrees, float(porticoAzimuth(0.0, there.azimuthDegrees)));
  EXPECT_NEAR(sydney.sunElevationDegrees, 32.7f, 0.5f);
  const float fromNorth = std::min(sydney.sunAzimuthDegrees, 360.0f - sydney.sunAzimuthDegrees);
  EXPECT_LT(fromNorth, 3.0f);   // +Z, north
}

TEST(SunTime, RefusesNoPlaceAndASunBelowTheHorizonInOneLine) {
  const std::string noPlace = resolveError(atTime("2026-06-21T12:00Z"), std::nullopt);
  EXPECT_NE(noPlace.find("--sun-time 2026-06-21T12:00:00Z: no place"), std::string::npos) << noPlace;
  EXPECT_NE(noPlace.find("--latitude and --longitude (scene /stores/house has no site)"), std::string::npos)
      << noPlace;
  // Tromsø at the December solstice's noon: polar night.
  const std::string night = resolveError(atTime("2026-12-21T11:45+01:00"), SiteLocation{69.6492, 18.9553, 0});
  EXPECT_NE(night.find("the sun is below the horizon at latitude 69.6492, longitude 18.9553 (elevation -3.0"),
            std::string::npos)
      << night;
  EXPECT_EQ(night.find('\n'), std::string::npos);
  DaylightSettings half = atTime("2026-06-21T12:00Z");
  half.sunTime->latitudeDegrees = 10.0;
  EXPECT_NE(resolveError(half, std::nullopt).find("--latitude and --longitude go together"), std::string::npos);
  half.sunTime->longitudeDegrees = 200.0;
  EXPECT_NE(daylightProblem(half).find("--longitude 200 must be a number of degrees from -180 to 180"),
            std::string::npos)
      << daylightProblem(half);
}

}  // namespace
}  // namespace portico
