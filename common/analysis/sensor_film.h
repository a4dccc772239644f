// How an analysis job's film holds its sensors' readings. Sensor i is row i
// of a film kSensorFilmColumns wide: its samples are dealt into
// sensorGroups(spp) groups (sample s into group s % groups), each an
// independent stratified estimate with patterns of its own, and each group
// adds its direct light (lamps, sky and sun through openings, by shadow
// rays) to one column and its indirect light (final gathering) to another.
// Every contribution is irradiance in W/m^2 weighed so that the row's sum is
// the mean of its groups' estimates: the reading. The spread of the groups'
// estimates gives the standard error, and direct over total the direct share.
// Film sums are order-free integers (film.h): the same bits on any number
// of workers.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "common/analysis/sensor.h"
#include "common/transport/film.h"

namespace portico {

// 16 groups: the standard error's own relative error is about 1/sqrt(2 x 15),
// 18 %; more columns would cost film for little.
constexpr uint32_t kSensorGroups = 16;
constexpr uint32_t kSensorFilmColumns = 2 * kSensorGroups;
// The most sensors of one job: kSensorFilmColumns x this is the largest film
// (2^28 pixels, job_limits.h).
constexpr uint32_t kMaxSensors = uint32_t(1) << 23;

inline uint32_t sensorGroups(uint32_t spp) { return std::clamp(spp, 1u, kSensorGroups); }
// Samples of group `group` (< groups): s = group, group + groups, ...
inline uint32_t samplesInGroup(uint32_t spp, uint32_t groups, uint32_t group) {
  return spp > group ? (spp - group + groups - 1) / groups : 0;
}
inline uint32_t directSlot(uint32_t sensor, uint32_t group) { return sensor * kSensorFilmColumns + group; }
inline uint32_t indirectSlot(uint32_t sensor, uint32_t group) {
  return sensor * kSensorFilmColumns + kSensorGroups + group;
}

// The reading of sensor `sensor` from the film (kSensorFilmColumns x
// sensors fixed-point sums), for a job of `spp` samples per sensor.
SensorReading sensorReading(const std::vector<FixedRgb>& film, uint32_t sensor, uint32_t spp);

}  // namespace portico
