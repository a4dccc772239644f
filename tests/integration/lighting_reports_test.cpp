// `portico analyze --grid auto` end to end with real workers: the grid is
// written beside the results as .pts and measured in its order; the
// per-room table agrees with the CSV's own readings, worked out here; a
// false-colour plan per floor is written; a bad --thresholds list is a
// one-line error before anything runs.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <nlohmann/json.hpp>

#include "tests/integration/analysis_csv.h"
#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;

const fs::path kTwoRooms = fs::path(PORTICO_SOURCE_DIR) / "tests" / "scenes" / "two_rooms";

class LightingReports : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = makeTempDirectory("lighting-reports");
    ASSERT_EQ(runCommand({kBin + "portico", "scene", "import", (kTwoRooms / "scene.json").string(), store().string()},
                         dir_ / "import.log"),
              0)
        << readFile(dir_ / "import.log");
  }
  static fs::path store() { return dir_ / "two_rooms"; }
  static int analyze(const fs::path& output, std::vector<std::string> extra = {}) {
    std::vector<std::string> argv{kBin + "portico", "analyze", store().string(), "-o", output.string(), "--grid",
                                  "auto", "--workers", "2", "--photons", "30000", "--spp", "8", "--gather", "4"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    return runCommand(argv, output.string() + ".log");
  }
  static inline fs::path dir_;
};

TEST_F(LightingReports, GridTableAndPlansBesideTheResults) {
  const fs::path output = dir_ / "RESULTS.csv";
  ASSERT_EQ(analyze(output, {"--thresholds", "20,50"}), 0) << readFile(output.string() + ".log");

  // The grid, as `scene grid` writes it, is the .pts beside the results, measured row by row.
  ASSERT_EQ(runCommand({kBin + "portico", "scene", "grid", store().string(), "-o", (dir_ / "grid.pts").string()},
                       dir_ / "grid.log"),
            0)
      << readFile(dir_ / "grid.log");
  const std::string pts = readFile(dir_ / "RESULTS.pts");
  EXPECT_EQ(pts, readFile(dir_ / "grid.pts"));
  const auto rows = csvRows(readFile(output));
  const auto numbers = csvNumbers(readFile(output));
  ASSERT_EQ(size_t(std::count(pts.begin(), pts.end(), '\n')), numbers.size());
  ASSERT_GT(numbers.size(), 20u);

  // Per room from the CSV: count, mean, min, max, shares at or above 20 and 50 lx.
  struct Room {
    std::vector<double> lux;
  };
  std::map<std::string, Room> rooms;
  for (size_t i = 0; i < numbers.size(); ++i) {
    EXPECT_EQ(numbers[i].at("dy"), 1.0);
    rooms[rows[i + 1][1]].lux.push_back(numbers[i].at("lux"));
  }
  ASSERT_EQ(rooms.size(), 2u);   // roomA and roomB; the door cell is too narrow for a point
  const auto table = nlohmann::json::parse(readFile(dir_ / "RESULTS.rooms.json"));
  ASSERT_EQ(table["rooms"].size(), 2u);
  EXPECT_EQ(table["thresholds_lux"], nlohmann::json({20, 50}));
  for (const auto& room : table["rooms"]) {
    const std::vector<double>& lux = rooms.at(room["room"].get<std::string>()).lux;
    double sum = 0;
    for (double v : lux) sum += v;
    const double mean = sum / double(lux.size());
    const double low = *std::min_element(lux.begin(), lux.end()), high = *std::max_element(lux.begin(), lux.end());
    EXPECT_EQ(room["sensors"].get<size_t>(), lux.size());
    // The CSV rounds lux to 6 digits.
    EXPECT_NEAR(room["mean_lux"].get<double>(), mean, 1e-5 * mean);
    EXPECT_NEAR(room["min_lux"].get<double>(), low, 1e-5 * low);
    EXPECT_NEAR(room["max_lux"].get<double>(), high, 1e-5 * high);
    EXPECT_NEAR(room["u0"].get<double>(), low / mean, 1e-4);
    for (double threshold : {20.0, 50.0}) {
      const double share = double(std::count_if(lux.begin(), lux.end(), [&](double v) { return v >= threshold; })) /
                           double(lux.size());
      EXPECT_NEAR(room["share_at_least_lux"][fmt::format("{}", threshold)].get<double>(), share, 1e-9);
    }
    EXPECT_GT(room["area_m2"].get<double>(), 0.0);
  }
  EXPECT_NE(readFile(dir_ / "RESULTS.rooms.csv").find("share_at_least_20_lux,share_at_least_50_lux"),
            std::string::npos);
  EXPECT_TRUE(fs::exists(dir_ / "RESULTS.floor0.png"));
  EXPECT_GT(fs::file_size(dir_ / "RESULTS.floor0.png"), 1000u);
}

TEST_F(LightingReports, BadThresholdsAreRefusedBeforeAnythingRuns) {
  const fs::path output = dir_ / "bad.csv";
  EXPECT_NE(analyze(output, {"--thresholds", "100,lots"}), 0);
  const std::string log = readFile(output.string() + ".log");
  EXPECT_NE(log.find("--thresholds 100,lots: 'lots' is not a number of lux >= 0"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(output));
  EXPECT_FALSE(fs::exists(dir_ / "bad.pts"));
}

}  // namespace
}  // namespace portico
