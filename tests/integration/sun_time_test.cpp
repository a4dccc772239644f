// A sun by date and time end to end: a building.json's "site" reaches the
// store and `scene info`; `render --sun-time` renders the same bits as
// `--sun AZ,EL` with the angles it resolved to (which the job's statistics
// show, and which are the solar model's); bad input is refused in one line.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>

#include "common/job/sun_time.h"
#include "common/transport/solar_position.h"
#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;

const fs::path kScene = fs::path(PORTICO_SOURCE_DIR) / "tests" / "scenes" / "daylight_window";
// Its openings are in the +X wall: with north at azimuth 5, the sun of a
// June evening in Karlsruhe (azimuth 281: a little north of west, portico
// azimuth 84) shines in through them.
constexpr const char* kSite = R"("site": {"latitude": 49.1003, "longitude": 8.4366, "north_azimuth": 5.0},)";
constexpr const char* kEvening = "2026-06-21T19:00+02:00";

class SunTime : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = makeTempDirectory("sun-time");
    fs::create_directories(dir_ / "scene");
    for (const auto& entry : fs::directory_iterator(kScene))
      if (entry.path().extension() != ".exr") fs::copy_file(entry.path(), dir_ / "scene" / entry.path().filename());
    std::string json = readFile(kScene / "scene.json");
    const std::string units = "\"units\": \"metres\",";
    ASSERT_NE(json.find(units), std::string::npos);
    std::ofstream(dir_ / "scene" / "sited.json") << json.replace(json.find(units), units.size(), units + kSite);
    ASSERT_EQ(importStore("sited.json", "sited"), 0) << readFile(dir_ / "sited.log");
    ASSERT_EQ(importStore("scene.json", "nowhere"), 0) << readFile(dir_ / "nowhere.log");
  }
  void TearDown() override { fs::remove_all(dir_); }
  int importStore(const std::string& json, const std::string& store) {
    return runCommand({kBin + "portico", "scene", "import", (dir_ / "scene" / json).string(), (dir_ / store).string()},
                      dir_ / (store + ".log"));
  }
  int render(const std::string& store, const std::string& output, const std::vector<std::string>& daylight) {
    std::vector<std::string> argv{kBin + "portico", "render", (dir_ / store).string(), "-o", (dir_ / output).string(),
                                  "--workers", "1", "--photons", "20000", "--spp", "1", "--width", "40", "--height",
                                  "30", "--sky", "uniform:0.8,0.9,1.1"};
    argv.insert(argv.end(), daylight.begin(), daylight.end());
    return runCommand(argv, dir_ / (output + ".log"));
  }
  // Exit code and log of a render expected to be refused; checks the refusal is one line.
  std::string refusal(const std::string& store, const std::vector<std::string>& daylight) {
    EXPECT_NE(render(store, "refused.exr", daylight), 0);
    EXPECT_FALSE(fs::exists(dir_ / "refused.exr"));
    return readFile(dir_ / "refused.exr.log");
  }
  fs::path dir_;
};

TEST_F(SunTime, SceneInfoShowsTheSite) {
  int code = 0;
  const auto info = nlohmann::json::parse(
      captureOutput({kBin + "portico", "scene", "info", (dir_ / "sited").string(), "--json"}, dir_, "info", &code));
  EXPECT_EQ(code, 0);
  EXPECT_EQ(info["site"], nlohmann::json::parse(R"({"latitude": 49.1003, "longitude": 8.4366, "north_azimuth": 5.0})"));
  const std::string text = captureOutput({kBin + "portico", "scene", "info", (dir_ / "sited").string()}, dir_, "text", &code);
  EXPECT_NE(text.find("site: latitude 49.1003, longitude 8.4366, north at azimuth 5"), std::string::npos) << text;
  const auto nowhere = nlohmann::json::parse(
      captureOutput({kBin + "portico", "scene", "info", (dir_ / "nowhere").string(), "--json"}, dir_, "nowhere", &code));
  EXPECT_TRUE(nowhere["site"].is_null());
}

TEST_F(SunTime, RendersTheSameBitsAsSunWithTheAnglesItResolvedTo) {
  ASSERT_EQ(render("sited", "timed.exr", {"--sun-time", kEvening}), 0) << readFile(dir_ / "timed.exr.log");
  const auto timed = nlohmann::json::parse(readFile(dir_ / "timed.exr.json"));
  const auto& daylight = timed["settings"]["daylight"];
  ASSERT_TRUE(daylight["sun"].get<bool>()) << timed["settings"].dump();
  const float azimuth = daylight["sun_azimuth"].get<float>(), elevation = daylight["sun_elevation"].get<float>();
  // The solar model's sun at the store's site, turned by its north.
  const SolarPosition sun = solarPosition(parseIsoInstant(kEvening), 49.1003, 8.4366);
  EXPECT_EQ(azimuth, float(porticoAzimuth(5.0, sun.azimuthDegrees)));
  EXPECT_EQ(elevation, float(sun.elevationDegrees));
  EXPECT_NEAR(sun.azimuthDegrees, 281, 2);   // a little north of west at 17:00 UTC
  EXPECT_GT(sun.elevationDegrees, 10);
  EXPECT_NE(readFile(dir_ / "timed.exr.log").find(fmt::format("sun: --sun {:.2f},{:.2f}", azimuth, elevation)),
            std::string::npos)
      << readFile(dir_ / "timed.exr.log");

  const std::string angles = daylight["sun_azimuth"].dump() + "," + daylight["sun_elevation"].dump();
  ASSERT_EQ(render("sited", "angles.exr", {"--sun", angles}), 0) << readFile(dir_ / "angles.exr.log");
  const auto given = nlohmann::json::parse(readFile(dir_ / "angles.exr.json"));
  EXPECT_EQ(given["settings"]["daylight"], timed["settings"]["daylight"]);
  EXPECT_EQ(given["photons"], timed["photons"]);
  EXPECT_EQ(differingFloats(dir_ / "timed.exr", dir_ / "angles.exr"), 0u);
  // Sunlight came in: photons left again through the openings.
  EXPECT_GT(timed["photons"]["escaped"].get<int64_t>(), 0);

  // The job's own place and north override the store's site.
  ASSERT_EQ(render("nowhere", "placed.exr",
                   {"--sun-time", kEvening, "--latitude", "49.1003", "--longitude", "8.4366", "--north-azimuth", "5"}),
            0)
      << readFile(dir_ / "placed.exr.log");
  EXPECT_EQ(differingFloats(dir_ / "timed.exr", dir_ / "placed.exr"), 0u);
}

TEST_F(SunTime, BadInputIsRefusedInOneLine) {
  std::string log = refusal("sited", {"--sun-time", "2026-06-21T19:00"});
  EXPECT_NE(log.find("has no UTC offset"), std::string::npos) << log;
  log = refusal("sited", {"--sun-time", kEvening, "--sun", "110,35"});
  EXPECT_NE(log.find("--sun"), std::string::npos) << log;
  EXPECT_NE(log.find("excludes"), std::string::npos) << log;
  log = refusal("nowhere", {"--sun-time", kEvening});
  EXPECT_NE(log.find("no place to see the sun from: give --latitude and --longitude"), std::string::npos) << log;
  log = refusal("sited", {"--sun-time", "2026-12-21T23:00+01:00"});
  EXPECT_NE(log.find("the sun is below the horizon at latitude 49.1003, longitude 8.4366 (elevation -"),
            std::string::npos)
      << log;
  log = refusal("sited", {"--latitude", "50"});
  EXPECT_NE(log.find("--latitude requires --sun-time"), std::string::npos) << log;
  log = refusal("sited", {"--sun-time", kEvening, "--latitude", "95"});
  EXPECT_NE(log.find("--latitude"), std::string::npos) << log;
  EXPECT_NE(log.find("95"), std::string::npos) << log;
}

}  // namespace
}  // namespace portico
