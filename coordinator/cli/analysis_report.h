// The reports of a lighting analysis (docs/lighting-reports.md), made from
// its results CSV and its store: the per-room table (RESULTS.rooms.csv and
// .json, common/analysis/room_table.h) and a false-colour plan per floor of
// its upward sensors (RESULTS.floorN.png, false_color_plan.h), in lux, or
// in % for a daylight-factor run. `portico analyze` writes them when its
// job is done; `portico report` makes them from any results file (a
// `submit --analyze` job's, fetched).
#pragma once

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

#include "common/analysis/sensor.h"
#include "common/scene/store/scene_store.h"
#include "coordinator/cli/command_table.h"

namespace portico::cli {

// A results CSV read back: the measured sensors (rows with readings), each
// located in the store's cell holding it as the coordinator locates them,
// with their readings; the daylight factor per sensor when the file has one.
struct AnalysisRows {
  std::vector<Sensor> sensors;
  std::vector<SensorReading> readings;
  std::vector<double> daylightFactors;   // % per sensor; empty: no daylight_factor column
};

// Throws std::runtime_error "PATH:LINE: problem" when the file cannot be
// read, lacks a column, or a field is not a number.
AnalysisRows readAnalysisRows(const std::string& resultsPath, const SceneStore& store);

// Writes the room tables and the plans beside `resultsPath`; returns the
// files written.
std::vector<std::string> writeAnalysisReport(const std::string& storeDirectory, const std::string& resultsPath,
                                             const std::vector<double>& thresholds);

// --thresholds, of `analyze` and `report`.
void addThresholdsOption(CLI::App& command, std::string& thresholds);

// `portico report STORE RESULTS.csv [--thresholds ...]`.
void addReportCommand(CLI::App& app, CommandTable& table);

}  // namespace portico::cli
