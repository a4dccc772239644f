// The per-room table of a lighting analysis (RESULTS.rooms.csv and .json):
// per room, how much light its sensors read and how much of its area meets
// each threshold; for a daylight-factor run, its daylight factor too.
//
// Sensors are grouped by cell (a room is a cell); sensors outside every
// cell (cell -1) are in no room. Each sensor of a room stands for an equal
// share of its area, as on a regular grid, so "share of area" is the share
// of its sensors.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "common/analysis/sensor.h"

namespace portico {

constexpr double kDaylightFactorTarget = 2.0;   // percent: the share reported is DF >= this

struct RoomTableOptions {
  std::vector<double> thresholds{100, 300, 500};   // lux
  // Lux of the unobstructed horizontal illuminance under the same sky: set
  // for a daylight-factor run, where DF = 100 x lux / this per sensor.
  std::optional<double> outdoorIlluminance;
  std::map<int64_t, double> floorArea;             // m^2 per cell, where known (--grid auto)
};

struct RoomSummary {
  int64_t cell = -1;
  std::string room;
  uint32_t sensors = 0;
  std::optional<double> area;                // m^2 of floor, when known
  double meanLux = 0, minLux = 0, maxLux = 0;
  double uniformity = 0;                     // U0 = min / mean; 0 when the mean is 0
  std::vector<double> shareAtOrAbove;        // per threshold: share of sensors with lux >= it
  // Daylight-factor runs only (percent).
  double meanDaylightFactor = 0, medianDaylightFactor = 0;
  double shareDaylightFactorAtOrAboveTarget = 0;
};

// `readings` holds one reading per sensor, in the same order. Rooms by cell
// id. Throws std::invalid_argument when the sizes differ or the outdoor
// illuminance is not positive.
std::vector<RoomSummary> summarizeRooms(const std::vector<Sensor>& sensors, const std::vector<SensorReading>& readings,
                                        const RoomTableOptions& options);

// "100,300,500" -> {100, 300, 500}. Throws std::runtime_error with a
// one-line message naming --thresholds and the bad item when an item is
// empty, not a number, negative or not finite.
std::vector<double> parseThresholds(std::string_view text);

std::string roomTableCsv(const std::vector<RoomSummary>& rooms, const RoomTableOptions& options);
std::string roomTableJson(const std::vector<RoomSummary>& rooms, const RoomTableOptions& options);

// RESULTS.csv -> RESULTS.rooms.csv and RESULTS.rooms.json beside it
// (the last extension replaced; appended when there is none).
std::string roomTablePath(const std::string& resultsPath, const std::string& extension);

// Writes both tables atomically beside `resultsPath`.
void writeRoomTables(const std::string& resultsPath, const std::vector<RoomSummary>& rooms,
                     const RoomTableOptions& options);

}  // namespace portico
