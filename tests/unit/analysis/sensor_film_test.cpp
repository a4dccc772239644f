// An analysis job's film read back as sensor readings: the mean of the
// groups' estimates, the standard error from their spread, the direct share.
#include <gtest/gtest.h>

#include <cmath>

#include "common/analysis/sensor_film.h"

namespace portico {
namespace {

TEST(SensorFilm, AReadingIsTheMeanOfItsGroupsWithTheStandardErrorOfTheirSpread) {
  const uint32_t sensors = 3, spp = 64;
  const uint32_t groups = sensorGroups(spp);
  ASSERT_EQ(groups, kSensorGroups);
  std::vector<FixedRgb> film(kSensorFilmColumns * sensors);
  // Sensor 1: group g estimates (2 + g % 2) W/m^2 of white light, a quarter
  // of it direct; each column holds its group's estimate over `groups`.
  std::vector<double> estimates;
  for (uint32_t g = 0; g < groups; ++g) {
    const double estimate = 2.0 + g % 2;
    estimates.push_back(estimate);
    film[directSlot(1, g)] = toFixed(Vec3(float(0.25 * estimate / groups)));
    film[indirectSlot(1, g)] = toFixed(Vec3(float(0.75 * estimate / groups)));
  }
  const SensorReading reading = sensorReading(film, 1, spp);
  EXPECT_NEAR(reading.irradiance.x, 2.5, 1e-5);
  EXPECT_NEAR(reading.lux, 179 * 2.5, 1e-3);
  double squares = 0;
  for (double e : estimates) squares += (179 * e - 179 * 2.5) * (179 * e - 179 * 2.5);
  EXPECT_NEAR(reading.standardError, std::sqrt(squares / (groups * (groups - 1.0))), 1e-3);
  EXPECT_NEAR(reading.directShare, 0.25, 1e-5);
  // Its neighbours' rows are untouched: dark, with nothing to share.
  EXPECT_EQ(sensorReading(film, 0, spp).lux, 0.0);
  EXPECT_EQ(sensorReading(film, 2, spp).directShare, 0.0);
}

TEST(SensorFilm, FewerSamplesThanGroupsMakeOneGroupEach) {
  EXPECT_EQ(sensorGroups(5), 5u);
  EXPECT_EQ(sensorGroups(1), 1u);
  uint32_t total = 0;
  for (uint32_t g = 0; g < sensorGroups(100); ++g) total += samplesInGroup(100, sensorGroups(100), g);
  EXPECT_EQ(total, 100u);   // every sample in exactly one group
  EXPECT_EQ(samplesInGroup(100, 16, 3), 7u);
  EXPECT_EQ(samplesInGroup(100, 16, 4), 6u);
}

}  // namespace
}  // namespace portico
