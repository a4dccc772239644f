#include "common/analysis/room_table.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "common/analysis/result_paths.h"
#include "common/util/atomic_file.h"
#include "common/util/csv_field.h"

namespace portico {

namespace {

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

double shareAtOrAbove(const std::vector<double>& values, double threshold) {
  const auto count = std::count_if(values.begin(), values.end(), [&](double v) { return v >= threshold; });
  return double(count) / double(values.size());
}

// Threshold column names: "100" for 100, "0.5" for 0.5.
std::string thresholdName(double threshold) { return fmt::format("{}", threshold); }

}  // namespace

std::vector<RoomSummary> summarizeRooms(const std::vector<Sensor>& sensors, const std::vector<SensorReading>& readings,
                                        const RoomTableOptions& options) {
  if (sensors.size() != readings.size())
    throw std::invalid_argument(
        fmt::format("room table: {} sensors but {} readings", sensors.size(), readings.size()));
  if (options.outdoorIlluminance && !(*options.outdoorIlluminance > 0 && std::isfinite(*options.outdoorIlluminance)))
    throw std::invalid_argument(
        fmt::format("room table: outdoor illuminance {} lx is not positive", *options.outdoorIlluminance));
  std::map<int64_t, std::vector<size_t>> byCell;
  for (size_t i = 0; i < sensors.size(); ++i)
    if (sensors[i].cell >= 0) byCell[sensors[i].cell].push_back(i);

  std::vector<RoomSummary> rooms;
  for (const auto& [cell, members] : byCell) {
    RoomSummary room;
    room.cell = cell;
    room.room = sensors[members.front()].room;
    room.sensors = uint32_t(members.size());
    if (auto it = options.floorArea.find(cell); it != options.floorArea.end()) room.area = it->second;
    std::vector<double> lux;
    for (size_t i : members) lux.push_back(readings[i].lux);
    double sum = 0;
    for (double v : lux) sum += v;   // in sensor order: the same bits every time
    room.meanLux = sum / double(lux.size());
    room.minLux = *std::min_element(lux.begin(), lux.end());
    room.maxLux = *std::max_element(lux.begin(), lux.end());
    room.uniformity = room.meanLux > 0 ? room.minLux / room.meanLux : 0;
    for (double threshold : options.thresholds) room.shareAtOrAbove.push_back(shareAtOrAbove(lux, threshold));
    if (options.outdoorIlluminance) {
      std::vector<double> factors;
      for (double v : lux) factors.push_back(100.0 * v / *options.outdoorIlluminance);
      double total = 0;
      for (double f : factors) total += f;
      room.meanDaylightFactor = total / double(factors.size());
      room.medianDaylightFactor = median(factors);
      room.shareDaylightFactorAtOrAboveTarget = shareAtOrAbove(factors, kDaylightFactorTarget);
    }
    rooms.push_back(std::move(room));
  }
  return rooms;
}

std::vector<double> parseThresholds(std::string_view text) {
  std::vector<double> thresholds;
  size_t start = 0;
  while (true) {
    const size_t comma = text.find(',', start);
    const std::string_view item = text.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start);
    double value = 0;
    const auto [end, error] = std::from_chars(item.data(), item.data() + item.size(), value);
    if (item.empty() || error != std::errc() || end != item.data() + item.size() || !std::isfinite(value) || value < 0)
      throw std::runtime_error(fmt::format(
          "--thresholds {}: '{}' is not a number of lux >= 0 (expected a list like 100,300,500)", text, item));
    thresholds.push_back(value);
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return thresholds;
}

std::string roomTableCsv(const std::vector<RoomSummary>& rooms, const RoomTableOptions& options) {
  std::string text = "cell,room,sensors,area_m2,mean_lux,min_lux,max_lux,u0";
  for (double threshold : options.thresholds) text += fmt::format(",share_at_least_{}_lux", thresholdName(threshold));
  if (options.outdoorIlluminance)
    text += fmt::format(",df_mean_percent,df_median_percent,df_share_at_least_{}_percent", kDaylightFactorTarget);
  text += "\n";
  for (const RoomSummary& r : rooms) {
    text += fmt::format("{},{},{},{},{:.6g},{:.6g},{:.6g},{:.4f}", r.cell, csvField(r.room), r.sensors,
                        r.area ? fmt::format("{:.3f}", *r.area) : "", r.meanLux, r.minLux, r.maxLux, r.uniformity);
    for (double share : r.shareAtOrAbove) text += fmt::format(",{:.4f}", share);
    if (options.outdoorIlluminance)
      text += fmt::format(",{:.4f},{:.4f},{:.4f}", r.meanDaylightFactor, r.medianDaylightFactor,
                          r.shareDaylightFactorAtOrAboveTarget);
    text += "\n";
  }
  return text;
}

std::string roomTableJson(const std::vector<RoomSummary>& rooms, const RoomTableOptions& options) {
  nlohmann::ordered_json table;
  table["thresholds_lux"] = options.thresholds;
  if (options.outdoorIlluminance) {
    table["outdoor_illuminance_lux"] = *options.outdoorIlluminance;
    table["daylight_factor_target_percent"] = kDaylightFactorTarget;
  }
  table["rooms"] = nlohmann::ordered_json::array();
  for (const RoomSummary& r : rooms) {
    nlohmann::ordered_json room;
    room["cell"] = r.cell;
    room["room"] = r.room;
    room["sensors"] = r.sensors;
    room["area_m2"] = r.area ? nlohmann::ordered_json(*r.area) : nlohmann::ordered_json();
    room["mean_lux"] = r.meanLux;
    room["min_lux"] = r.minLux;
    room["max_lux"] = r.maxLux;
    room["u0"] = r.uniformity;
    nlohmann::ordered_json shares = nlohmann::ordered_json::object();
    for (size_t k = 0; k < options.thresholds.size(); ++k)
      shares[thresholdName(options.thresholds[k])] = r.shareAtOrAbove[k];
    room["share_at_least_lux"] = shares;
    if (options.outdoorIlluminance) {
      room["df_mean_percent"] = r.meanDaylightFactor;
      room["df_median_percent"] = r.medianDaylightFactor;
      room["df_share_at_least_target"] = r.shareDaylightFactorAtOrAboveTarget;
    }
    table["rooms"].push_back(std::move(room));
  }
  return table.dump(1) + "\n";
}

std::string roomTablePath(const std::string& resultsPath, const std::string& extension) {
  return besideResults(resultsPath, ".rooms." + extension);
}

void writeRoomTables(const std::string& resultsPath, const std::vector<RoomSummary>& rooms,
                     const RoomTableOptions& options) {
  writeFileAtomically(roomTablePath(resultsPath, "csv"), roomTableCsv(rooms, options));
  writeFileAtomically(roomTablePath(resultsPath, "json"), roomTableJson(rooms, options));
}

}  // namespace portico
