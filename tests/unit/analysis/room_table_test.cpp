// The per-room table against statistics worked out by hand, its CSV and
// JSON, and the --thresholds parser's errors.
#include "common/analysis/room_table.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

namespace portico {
namespace {

Sensor sensorIn(int64_t cell, const std::string& room) {
  Sensor s;
  s.cell = cell;
  s.room = room;
  s.direction = Vec3(0, 1, 0);
  return s;
}

SensorReading readingOf(double lux) {
  SensorReading r;
  r.lux = lux;
  return r;
}

// Room 3 "office, north" reads 100, 600, 200, 300 lx; room 1 "hall" 50 lx;
// one sensor lies outside every cell.
struct Readings {
  std::vector<Sensor> sensors{sensorIn(3, "office, north"), sensorIn(1, "hall"),         sensorIn(3, "office, north"),
                              sensorIn(-1, ""),             sensorIn(3, "office, north"), sensorIn(3, "office, north")};
  std::vector<SensorReading> readings{readingOf(100), readingOf(50), readingOf(600),
                                      readingOf(9999), readingOf(200), readingOf(300)};
};

TEST(RoomTable, StatisticsMatchTheHandWorkedValues) {
  const Readings r;
  RoomTableOptions options;
  options.floorArea[3] = 24.5;
  const std::vector<RoomSummary> rooms = summarizeRooms(r.sensors, r.readings, options);
  ASSERT_EQ(rooms.size(), 2u);   // by cell id; the sensor outside every cell is in none
  const RoomSummary& hall = rooms[0];
  EXPECT_EQ(hall.cell, 1);
  EXPECT_EQ(hall.sensors, 1u);
  EXPECT_FALSE(hall.area.has_value());
  EXPECT_DOUBLE_EQ(hall.uniformity, 1.0);
  EXPECT_EQ(hall.shareAtOrAbove, (std::vector<double>{0, 0, 0}));
  const RoomSummary& office = rooms[1];
  EXPECT_EQ(office.room, "office, north");
  EXPECT_EQ(office.sensors, 4u);
  EXPECT_DOUBLE_EQ(*office.area, 24.5);
  EXPECT_DOUBLE_EQ(office.meanLux, 300.0);   // (100 + 600 + 200 + 300) / 4
  EXPECT_DOUBLE_EQ(office.minLux, 100.0);
  EXPECT_DOUBLE_EQ(office.maxLux, 600.0);
  EXPECT_DOUBLE_EQ(office.uniformity, 1.0 / 3.0);
  // >= 100: all four; >= 300: 600 and 300; >= 500: 600.
  EXPECT_EQ(office.shareAtOrAbove, (std::vector<double>{1.0, 0.5, 0.25}));
}

TEST(RoomTable, DaylightFactorRunsAddMeanMedianAndShareAboveTwoPercent) {
  const Readings r;
  RoomTableOptions options;
  options.outdoorIlluminance = 10000;   // DF = 1, 6, 2, 3 % in the office
  const std::vector<RoomSummary> rooms = summarizeRooms(r.sensors, r.readings, options);
  EXPECT_DOUBLE_EQ(rooms[1].meanDaylightFactor, 3.0);
  EXPECT_DOUBLE_EQ(rooms[1].medianDaylightFactor, 2.5);              // (2 + 3) / 2
  EXPECT_DOUBLE_EQ(rooms[1].shareDaylightFactorAtOrAboveTarget, 0.75);   // 6, 2, 3
  EXPECT_DOUBLE_EQ(rooms[0].medianDaylightFactor, 0.5);
  options.outdoorIlluminance = 0;
  EXPECT_THROW(summarizeRooms(r.sensors, r.readings, options), std::invalid_argument);
}

TEST(RoomTable, CsvAndJsonCarryEveryColumn) {
  const Readings r;
  RoomTableOptions options;
  options.thresholds = {300, 0.5};
  options.outdoorIlluminance = 10000;
  options.floorArea[3] = 24.5;
  const auto rooms = summarizeRooms(r.sensors, r.readings, options);
  EXPECT_EQ(roomTableCsv(rooms, options),
            "cell,room,sensors,area_m2,mean_lux,min_lux,max_lux,u0,share_at_least_300_lux,share_at_least_0.5_lux,"
            "df_mean_percent,df_median_percent,df_share_at_least_2_percent\n"
            "1,hall,1,,50,50,50,1.0000,0.0000,1.0000,0.5000,0.5000,0.0000\n"
            "3,\"office, north\",4,24.500,300,100,600,0.3333,0.5000,1.0000,3.0000,2.5000,0.7500\n");
  const auto json = nlohmann::json::parse(roomTableJson(rooms, options));
  EXPECT_EQ(json["thresholds_lux"], nlohmann::json({300, 0.5}));
  EXPECT_EQ(json["outdoor_illuminance_lux"], 10000);
  ASSERT_EQ(json["rooms"].size(), 2u);
  EXPECT_TRUE(json["rooms"][0]["area_m2"].is_null());
  EXPECT_EQ(json["rooms"][1]["room"], "office, north");
  EXPECT_DOUBLE_EQ(json["rooms"][1]["share_at_least_lux"]["300"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(json["rooms"][1]["df_median_percent"].get<double>(), 2.5);
}

TEST(RoomTable, PathsSitBesideTheResults) {
  EXPECT_EQ(roomTablePath("out/RESULTS.csv", "csv"), "out/RESULTS.rooms.csv");
  EXPECT_EQ(roomTablePath("out/RESULTS.csv", "json"), "out/RESULTS.rooms.json");
  EXPECT_EQ(roomTablePath("out.d/results", "csv"), "out.d/results.rooms.csv");
  EXPECT_EQ(roomTablePath(".hidden", "csv"), ".hidden.rooms.csv");
}

TEST(Thresholds, ParseListsAndRejectWhatIsNotANumber) {
  EXPECT_EQ(parseThresholds("100,300,500"), (std::vector<double>{100, 300, 500}));
  EXPECT_EQ(parseThresholds("0.5"), (std::vector<double>{0.5}));
  const auto errorOf = [](const char* text) -> std::string {
    try {
      parseThresholds(text);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(errorOf("100,abc"), "--thresholds 100,abc: 'abc' is not a number of lux >= 0 (expected a list like 100,300,500)");
  EXPECT_NE(errorOf("100,,300").find("'' is not a number"), std::string::npos);
  EXPECT_NE(errorOf("-5").find("'-5'"), std::string::npos);
  EXPECT_NE(errorOf("nan").find("'nan'"), std::string::npos);
  EXPECT_NE(errorOf("300lx").find("'300lx'"), std::string::npos);
  EXPECT_NE(errorOf("").find("''"), std::string::npos);
}

}  // namespace
}  // namespace portico
