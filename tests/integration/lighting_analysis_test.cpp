// `portico analyze` and `portico submit --analyze` end to end with real
// workers: a Radiance .pts file in, one CSV row per sensor in the file's
// order out, the same bytes on one or two workers; a sensor outside every
// cell keeps its row with empty readings; a bad line is refused naming the
// file and the line, before anything runs.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/integration/analysis_csv.h"
#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;

const fs::path kCornell = fs::path(PORTICO_SOURCE_DIR) / "tests" / "scenes" / "cornell_closed";

class LightingAnalysis : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = makeTempDirectory("lighting-analysis");
    ASSERT_EQ(runCommand({kBin + "portico", "scene", "import", (kCornell / "scene.json").string(), store().string()},
                         dir_ / "import.log"),
              0)
        << readFile(dir_ / "import.log");
  }
  static fs::path store() { return dir_ / "cornell"; }
  static fs::path writePts(const std::string& name, const std::string& text) {
    const fs::path path = dir_ / name;
    std::ofstream(path) << text;
    return path;
  }
  // `portico analyze` with small sampling; returns the exit code.
  static int analyze(const fs::path& sensors, const fs::path& output, int workers, std::vector<std::string> extra = {}) {
    std::vector<std::string> argv{kBin + "portico", "analyze", store().string(), "-o", output.string(), "--sensors",
                                  sensors.string(), "--workers", std::to_string(workers), "--photons", "30000",
                                  "--spp", "16", "--gather", "4"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    return runCommand(argv, output.string() + ".log");
  }
  static inline fs::path dir_;
};

// Nine sensors: eight across the Cornell box (up over the floor, down
// under the ceiling, sideways at the walls) and one far outside it on line
// 6; a comment and a blank line.
constexpr const char* kSensors =
    "# x y z dx dy dz\n"
    "0 0.8 0.5 0 1 0\n"
    "-0.5 0.8 1.5 0 1 0\n"
    "\n"
    "0.5 0.8 -0.5 0 1 0\n"
    "5 5 5 0 1 0\n"
    "0 1.5 0 0 -1 0\n"
    "-0.9 1 0.5 1 0 0\n"
    "0.9 1 0.5 -2 0 0\n"
    "0\t1\t1.9\t0\t0\t-1\n"
    "0.2 0.05 1.5 0 1 0\n";

TEST_F(LightingAnalysis, OneRowPerSensorInFileOrderWithTheSameBytesOnOneOrTwoWorkers) {
  const fs::path sensors = writePts("room.pts", kSensors);
  ASSERT_EQ(analyze(sensors, dir_ / "one.csv", 1), 0) << readFile(dir_ / "one.csv.log");
  ASSERT_EQ(analyze(sensors, dir_ / "two.csv", 2), 0) << readFile(dir_ / "two.csv.log");
  const std::string one = readFile(dir_ / "one.csv"), two = readFile(dir_ / "two.csv");
  EXPECT_EQ(one, two);
  // The sensor outside every cell is named by its line before the job runs.
  EXPECT_NE(readFile(dir_ / "one.csv.log").find("room.pts line 6"), std::string::npos) << readFile(dir_ / "one.csv.log");

  const auto rows = csvRows(one);
  ASSERT_EQ(rows.size(), 10u) << one;
  EXPECT_EQ(rows[0], (std::vector<std::string>{"index", "room", "x", "y", "z", "dx", "dy", "dz", "irradiance_r",
                                               "irradiance_g", "irradiance_b", "lux", "standard_error_lux",
                                               "direct_share"}));
  const std::vector<std::string> xs{"0", "-0.5", "0.5", "5", "0", "-0.9", "0.9", "0", "0.2"};
  for (size_t i = 1; i < rows.size(); ++i) {
    const auto& row = rows[i];
    ASSERT_EQ(row.size(), 14u) << one;
    EXPECT_EQ(row[0], std::to_string(i - 1));
    if (i - 1 < xs.size()) EXPECT_EQ(row[2], xs[i - 1]);   // the file's order
    if (i == 4) {
      // Outside every cell: no room, no reading.
      EXPECT_EQ(row[1], "");
      for (size_t c = 8; c < 14; ++c) EXPECT_EQ(row[c], "") << one;
      continue;
    }
    const double lux = std::stod(row[11]), error = std::stod(row[12]), direct = std::stod(row[13]);
    EXPECT_GT(lux, 0) << row[0];
    EXPECT_GT(error, 0) << row[0];
    EXPECT_LT(error, 0.5 * lux) << row[0];
    EXPECT_GE(direct, 0) << row[0];
    EXPECT_LE(direct, 1) << row[0];
    // lux = 179 x Rec. 709 Y of the irradiance.
    const double y = 0.2126 * std::stod(row[8]) + 0.7152 * std::stod(row[9]) + 0.0722 * std::stod(row[10]);
    EXPECT_NEAR(lux, 179 * y, 1e-3 * lux) << row[0];
  }
  // Under the lamp, facing it, the floor sensor is mostly lit directly; the
  // one under the ceiling facing down sees no lamp: indirect light only.
  EXPECT_GT(std::stod(rows[1][13]), 0.5);
  EXPECT_EQ(std::stod(rows[5][13]), 0.0);
  EXPECT_GT(std::stod(rows[5][11]), 0.0);
  // The red wall reflects more red onto a sensor facing it than the green one does.
  EXPECT_GT(std::stod(rows[7][8]) / std::stod(rows[7][9]), std::stod(rows[6][8]) / std::stod(rows[6][9]));

  const auto stats = nlohmann::json::parse(readFile(dir_ / "one.csv.json"));
  EXPECT_EQ(stats["analysis"]["sensors"], 9);
  EXPECT_EQ(stats["analysis"]["outside_cells"], 1);
  EXPECT_EQ(stats["analysis"]["measured"], 8);
  // Each measured sensor's samples count as camera rays.
  EXPECT_EQ(stats["rays"]["camera"], 8 * 16);
  EXPECT_EQ(stats["rays"]["queued"], 0);
  EXPECT_GE(stats["rays"]["shadow"].get<int64_t>(),
            stats["rays"]["shadow_blocked"].get<int64_t>() + stats["rays"]["shadow_reached"].get<int64_t>());
}

TEST_F(LightingAnalysis, SubmitAnalyzeToARunningCoordinatorWritesTheSameResults) {
  const fs::path sensors = writePts("submit.pts", kSensors);
  ASSERT_EQ(analyze(sensors, dir_ / "local.csv", 2), 0) << readFile(dir_ / "local.csv.log");
  LocalCluster cluster(dir_ / "cluster", 2);
  int code = 0;
  const std::string id = captureOutput({kBin + "portico", "submit", "--coordinator", cluster.endpoint(), "--analyze",
                                        "--sensors", sensors.string(), store().string(), "-o",
                                        (dir_ / "submitted.csv").string(), "--photons", "30000", "--spp", "16",
                                        "--gather", "4"},
                                       dir_, "submit", &code);
  ASSERT_EQ(code, 0) << readFile(dir_ / "submit.log");
  const auto status = cluster.wait(std::stoull(id));
  ASSERT_EQ(status["state"], "done") << status.dump();
  EXPECT_EQ(readFile(dir_ / "submitted.csv"), readFile(dir_ / "local.csv"));
}

TEST_F(LightingAnalysis, ABadSensorLineIsRefusedNamingTheFileAndLine) {
  const struct {
    const char* text;
    const char* problem;
  } cases[] = {{"0 1 0 0 1 0\n0 1 nan 0 1 0\n", "bad.pts:2:"},
               {"0 1 0 0 1 0\n\n0 1 0 0 0 0\n", "bad.pts:3: the direction dx dy dz is zero"},
               {"0 1 0 0 1\n", "bad.pts:1: 5 numbers, expected 6"},
               {"0 1 0 0 1 0 7\n", "bad.pts:1: more than 6 numbers"},
               {"# nothing\n", "no sensor"}};
  for (const auto& c : cases) {
    const fs::path sensors = writePts("bad.pts", c.text);
    fs::remove(dir_ / "bad.csv");
    EXPECT_NE(analyze(sensors, dir_ / "bad.csv", 1), 0) << c.text;
    const std::string log = readFile(dir_ / "bad.csv.log");
    EXPECT_NE(log.find(c.problem), std::string::npos) << log;
    EXPECT_FALSE(fs::exists(dir_ / "bad.csv"));
  }
  // Not a .csv, and no sensors at all: refused naming the option.
  const fs::path good = writePts("good.pts", "0 1 0 0 1 0\n");
  EXPECT_NE(analyze(good, dir_ / "results.png", 1), 0);
  EXPECT_NE(readFile(dir_ / "results.png.log").find(".csv"), std::string::npos) << readFile(dir_ / "results.png.log");
  EXPECT_NE(runCommand({kBin + "portico", "analyze", store().string(), "-o", (dir_ / "none.csv").string()},
                       dir_ / "none.log"),
            0);
  EXPECT_NE(readFile(dir_ / "none.log").find("--sensors"), std::string::npos) << readFile(dir_ / "none.log");
  // Every sensor outside the building: refused by the coordinator.
  const fs::path outside = writePts("outside.pts", "50 1 0 0 1 0\n");
  EXPECT_NE(analyze(outside, dir_ / "outside.csv", 1), 0);
  EXPECT_NE(readFile(dir_ / "outside.csv.log").find("none of the 1 sensors"), std::string::npos)
      << readFile(dir_ / "outside.csv.log");
}

}  // namespace
}  // namespace portico
