// Reports from a results CSV: read back by column name (the CSV's layout is
// coordinator/analysis_results.h's), each measured row a sensor located in
// the store, then the room tables and the plans.
#include "coordinator/cli/analysis_report.h"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <fstream>
#include <iostream>
#include <map>
#include <stdexcept>

#include "common/analysis/room_table.h"
#include "common/analysis/work_plane_grid.h"
#include "coordinator/cli/false_color_plan.h"

namespace portico::cli {

namespace {

// One CSV record (RFC 4180: quoted fields, quotes doubled inside them).
std::vector<std::string> splitRecord(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted && c == '"' && i + 1 < line.size() && line[i + 1] == '"')
      fields.back() += '"', ++i;
    else if (c == '"')
      quoted = !quoted;
    else if (c == ',' && !quoted)
      fields.emplace_back();
    else
      fields.back() += c;
  }
  return fields;
}

class RowReader {
 public:
  RowReader(std::string path, const std::vector<std::string>& header) : path_(std::move(path)) {
    for (size_t c = 0; c < header.size(); ++c) columns_[header[c]] = c;
  }
  bool has(const std::string& column) const { return columns_.count(column) > 0; }
  size_t column(const std::string& name) const {
    const auto it = columns_.find(name);
    if (it == columns_.end()) throw std::runtime_error(fmt::format("{}:1: no column '{}'", path_, name));
    return it->second;
  }
  double number(const std::vector<std::string>& fields, const std::string& name, size_t line) const {
    const std::string& text = fields.at(column(name));
    double value = 0;
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (text.empty() || error != std::errc() || end != text.data() + text.size() || !std::isfinite(value))
      throw std::runtime_error(fmt::format("{}:{}: {} '{}' is not a number", path_, line, name, text));
    return value;
  }

 private:
  std::string path_;
  std::map<std::string, size_t> columns_;
};

}  // namespace

AnalysisRows readAnalysisRows(const std::string& resultsPath, const SceneStore& store) {
  std::ifstream in(resultsPath);
  if (!in) throw std::runtime_error(fmt::format("cannot read the results {}", resultsPath));
  std::string line;
  if (!std::getline(in, line)) throw std::runtime_error(fmt::format("{}: empty, not the results of an analysis", resultsPath));
  const RowReader reader(resultsPath, splitRecord(line));
  const size_t lux = reader.column("lux");
  const bool daylight = reader.has("daylight_factor");
  AnalysisRows rows;
  for (size_t number = 2; std::getline(in, line); ++number) {
    const std::vector<std::string> fields = splitRecord(line);
    if (fields.size() <= lux) throw std::runtime_error(fmt::format("{}:{}: too few fields", resultsPath, number));
    if (fields[lux].empty()) continue;   // outside every cell: not measured
    Sensor sensor;
    sensor.position = Vec3(float(reader.number(fields, "x", number)), float(reader.number(fields, "y", number)),
                           float(reader.number(fields, "z", number)));
    sensor.direction = Vec3(float(reader.number(fields, "dx", number)), float(reader.number(fields, "dy", number)),
                            float(reader.number(fields, "dz", number)));
    if (const auto cell = store.locateCell(sensor.position)) {
      sensor.cell = *cell;
      sensor.room = store.cells()[*cell].name;
    }
    SensorReading reading;
    reading.irradiance = Vec3(float(reader.number(fields, "irradiance_r", number)),
                              float(reader.number(fields, "irradiance_g", number)),
                              float(reader.number(fields, "irradiance_b", number)));
    reading.lux = reader.number(fields, "lux", number);
    rows.sensors.push_back(std::move(sensor));
    rows.readings.push_back(reading);
    if (daylight) rows.daylightFactors.push_back(reader.number(fields, "daylight_factor", number));
  }
  return rows;
}

std::vector<std::string> writeAnalysisReport(const std::string& storeDirectory, const std::string& resultsPath,
                                             const std::vector<double>& thresholds) {
  const SceneStore store = SceneStore::open(storeDirectory);
  const AnalysisRows rows = readAnalysisRows(resultsPath, store);
  RoomTableOptions table;
  table.thresholds = thresholds;
  std::vector<double> values;
  for (const SensorReading& r : rows.readings) values.push_back(r.lux);
  if (!rows.daylightFactors.empty()) {
    // E_out from the file's own ratio DF = 100 E / E_out (the CSV keeps DF to 4 digits).
    double lux = 0, factors = 0;
    for (size_t i = 0; i < rows.readings.size(); ++i) lux += rows.readings[i].lux, factors += rows.daylightFactors[i];
    if (factors > 0) table.outdoorIlluminance = 100.0 * lux / factors;
    values = rows.daylightFactors;
  }
  for (const Sensor& s : rows.sensors)
    if (s.cell >= 0 && !table.floorArea.count(s.cell))
      if (const auto floor = findRoomFloor(store, uint32_t(s.cell))) table.floorArea[s.cell] = floor->area;
  writeRoomTables(resultsPath, summarizeRooms(rows.sensors, rows.readings, table), table);
  std::vector<std::string> written{roomTablePath(resultsPath, "csv"), roomTablePath(resultsPath, "json")};

  FalseColorPlanOptions plan;
  plan.scale.unit = rows.daylightFactors.empty() ? "lux" : "DF %";
  plan.title = rows.daylightFactors.empty() ? "illuminance" : "daylight factor";
  for (std::string& path : writeFalseColorPlans(resultsPath, store, rows.sensors, values, plan))
    written.push_back(std::move(path));
  return written;
}

void addThresholdsOption(CLI::App& command, std::string& thresholds) {
  command
      .add_option("--thresholds", thresholds,
                  "lux thresholds of the per-room table (RESULTS.rooms.csv): the share of each room's area at or "
                  "above each")
      ->capture_default_str();
}

void addReportCommand(CLI::App& app, CommandTable& table) {
  struct Options {
    std::string store, results, thresholds = "100,300,500";
  };
  auto o = std::make_shared<Options>();
  auto* report = app.add_subcommand(
      "report", "the per-room table and false-colour plans of an analysis's results CSV (as `analyze` writes them)");
  report->add_option("STORE", o->store, "the scene store analysed")->required()->check(CLI::ExistingDirectory);
  report->add_option("RESULTS", o->results, "the results .csv")->required()->check(CLI::ExistingFile);
  addThresholdsOption(*report, o->thresholds);
  table.add(report, [o] {
    const std::vector<double> thresholds = parseThresholds(o->thresholds);
    for (const std::string& path : writeAnalysisReport(o->store, o->results, thresholds)) std::cout << path << "\n";
    return 0;
  });
}

}  // namespace portico::cli
