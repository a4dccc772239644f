// A camera chosen at render time (`--look-from`, `--look-at`, `--up`,
// `--fov`, or a named store camera with `--camera NAME`), end to end through
// `portico render` with real workers; `scene info --json` listing the
// store's cameras.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "common/scene/store/scene_store.h"
#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;

class CameraChoice : public DemoStoreSuite<CameraChoice> {
 protected:
  static std::string text(const Vec3& v) { return fmt::format("{},{},{}", v.x, v.y, v.z); }

  // Renders a small image with `extra` options; returns the exit code.
  static int render(const std::string& name, int workers, const std::vector<std::string>& extra) {
    std::vector<std::string> argv{kBin + "portico", "render", store_.string(), "-o", (dir_ / (name + ".exr")).string(),
                                  "--workers", std::to_string(workers), "--photons", "20000", "--spp", "1",
                                  "--gather", "2", "--width", "48", "--height", "32"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    return runCommand(argv, dir_ / (name + ".log"));
  }
  static fs::path image(const std::string& name) { return dir_ / (name + ".exr"); }
};

TEST_F(CameraChoice, TheStoresOwnCameraGivenAsOptionsGivesTheDefaultImageBitForBit) {
  const Camera own = SceneStore::open(store_).camera();
  ASSERT_EQ(render("default", 2, {}), 0) << readFile(dir_ / "default.log");
  ASSERT_EQ(render("own", 2,
                   {"--look-from", text(own.origin), "--look-at", text(own.target), "--up", text(own.up), "--fov",
                    fmt::format("{}", own.fovYDegrees)}),
            0)
      << readFile(dir_ / "own.log");
  EXPECT_EQ(differingFloats(image("default"), image("own")), 0u);
}

TEST_F(CameraChoice, AnotherEyeGivesAnotherLitImageWithTheSameBitsForOneAndTwoWorkers) {
  const SceneStore scene = SceneStore::open(store_);
  const Camera& own = scene.camera();
  // Closer to the target, in whichever cell holds the new eye.
  const Vec3 eye = own.origin + (own.target - own.origin) * 0.3f;
  ASSERT_TRUE(scene.locateCell(eye).has_value());
  const std::vector<std::string> options{"--look-from", text(eye), "--look-at", text(own.target), "--fov", "50"};
  ASSERT_EQ(render("default-view", 1, {}), 0) << readFile(dir_ / "default-view.log");
  ASSERT_EQ(render("closer-one", 1, options), 0) << readFile(dir_ / "closer-one.log");
  ASSERT_EQ(render("closer-two", 2, options), 0) << readFile(dir_ / "closer-two.log");
  EXPECT_EQ(differingFloats(image("closer-one"), image("closer-two")), 0u);
  EXPECT_GT(differingFloats(image("closer-one"), image("default-view")), 0u);
  const LinearImage closer = readImage(image("closer-one").string());
  size_t lit = 0;
  for (float value : closer.rgb) lit += value > 0;
  EXPECT_GT(lit, closer.rgb.size() / 3);
}

// Each refusal is one line naming the option (followed, for the client's
// own checks, by CLI11's hint to run --help), and the exit code says so.
TEST_F(CameraChoice, BadCamerasAreRefusedInOneLineNamingTheOption) {
  const Camera own = SceneStore::open(store_).camera();
  const std::string at = text(own.target);
  struct Case {
    const char* name;
    std::vector<std::string> options;
    const char* option;
  };
  const std::vector<Case> cases{
      {"outside", {"--look-from", "1e6,1e6,1e6", "--look-at", at}, "--look-from"},
      {"same", {"--look-from", at, "--look-at", at}, "--look-at"},
      {"nan", {"--look-from", "nan,0,0", "--look-at", at}, "--look-from"},
      {"words", {"--look-from", "1,2", "--look-at", at}, "--look-from"},
      {"fov-zero", {"--look-from", text(own.origin), "--look-at", at, "--fov", "0"}, "--fov"},
      {"fov-wide", {"--look-from", text(own.origin), "--look-at", at, "--fov", "180"}, "--fov"},
      {"no-at", {"--look-from", text(own.origin)}, "--look-from"},
  };
  for (const Case& c : cases) {
    EXPECT_NE(render(c.name, 1, c.options), 0) << c.name;
    const std::string log = readFile(dir_ / (std::string(c.name) + ".log"));
    const size_t end = log.find('\n');
    const std::string first = log.substr(0, end), rest = end == std::string::npos ? "" : log.substr(end + 1);
    EXPECT_NE(first.find(c.option), std::string::npos) << c.name << ": " << log;
    EXPECT_TRUE(rest.empty() || rest == "Run with --help for more information.\n") << c.name << ": " << log;
  }
}

// `scene info --json` lists every named camera with its cell and placement,
// exactly as stored (a float printed as JSON reads back to the same float).
TEST_F(CameraChoice, SceneInfoListsEveryNamedCamera) {
  int code = -1;
  const std::string out =
      captureOutput({kBin + "portico", "scene", "info", "--json", "--no-compress", store_.string()}, dir_, "info", &code);
  ASSERT_EQ(code, 0) << readFile(dir_ / "info.log");
  const nlohmann::json cameras = nlohmann::json::parse(out).at("cameras");
  const SceneStore scene = SceneStore::open(store_);
  ASSERT_EQ(cameras.size(), scene.cameras().size());
  ASSERT_GE(cameras.size(), 3u);
  EXPECT_EQ(cameras[0].at("name"), "overview");
  for (size_t k = 0; k < cameras.size(); ++k) {
    const Camera& stored = scene.cameras()[k];
    EXPECT_EQ(cameras[k].at("name"), stored.name);
    EXPECT_EQ(cameras[k].at("cell"), stored.cell);
    for (int axis = 0; axis < 3; ++axis) {
      EXPECT_EQ(cameras[k].at("origin")[axis].get<float>(), stored.origin[axis]) << stored.name;
      EXPECT_EQ(cameras[k].at("look_at")[axis].get<float>(), stored.target[axis]) << stored.name;
      EXPECT_EQ(cameras[k].at("up")[axis].get<float>(), stored.up[axis]) << stored.name;
    }
    EXPECT_EQ(cameras[k].at("fov").get<float>(), stored.fovYDegrees) << stored.name;
  }
  const std::string plain = captureOutput({kBin + "portico", "scene", "info", "--no-compress", store_.string()}, dir_,
                                          "info-plain", &code);
  EXPECT_NE(plain.find(fmt::format("cameras ({}, ", cameras.size())), std::string::npos) << plain;
  EXPECT_NE(plain.find("overview, "), std::string::npos) << plain;
}

// `--camera NAME` renders the store camera as stored: the same bits as its
// placement given with --look-from, --look-at, --up and --fov, taken from
// `scene info --json`; another view than the default.
TEST_F(CameraChoice, ANamedCameraGivesTheBitsOfItsPlacementGivenAsOptions) {
  int code = -1;
  const std::string out =
      captureOutput({kBin + "portico", "scene", "info", "--json", "--no-compress", store_.string()}, dir_, "info-for-room", &code);
  ASSERT_EQ(code, 0) << readFile(dir_ / "info-for-room.log");
  const nlohmann::json info = nlohmann::json::parse(out);
  nlohmann::json room;
  for (const nlohmann::json& camera : info.at("cameras"))
    if (camera.at("name") == "room-2") room = camera;
  ASSERT_FALSE(room.is_null()) << out;
  const auto vec = [](const nlohmann::json& v) {
    return text(Vec3(v[0].get<float>(), v[1].get<float>(), v[2].get<float>()));
  };
  ASSERT_EQ(render("named", 2, {"--camera", "room-2"}), 0) << readFile(dir_ / "named.log");
  ASSERT_EQ(render("placed", 1,
                   {"--look-from", vec(room.at("origin")), "--look-at", vec(room.at("look_at")), "--up",
                    vec(room.at("up")), "--fov", fmt::format("{}", room.at("fov").get<float>())}),
            0)
      << readFile(dir_ / "placed.log");
  ASSERT_EQ(render("overview", 1, {"--camera", "overview"}), 0) << readFile(dir_ / "overview.log");
  EXPECT_EQ(differingFloats(image("named"), image("placed")), 0u);
  EXPECT_GT(differingFloats(image("named"), image("overview")), 0u);
  const LinearImage named = readImage(image("named").string());
  size_t lit = 0;
  for (float value : named.rgb) lit += value > 0;
  EXPECT_GT(lit, named.rgb.size() / 2) << "a view from a lit room's door is mostly lit";
  // Its top row shows the room's ceiling, which hides only from a camera
  // above it, not the dark sky beyond.
  size_t litTop = 0;
  for (size_t x = 0; x < 3 * size_t(named.width); ++x) litTop += named.rgb[x] > 0;
  EXPECT_GT(litTop, 3 * size_t(named.width) * 9 / 10);
}

// An unknown name, or a name beside --look-from: one line naming the camera
// (and some that exist) or both options.
TEST_F(CameraChoice, AnUnknownOrDoubleCameraChoiceIsRefusedInOneLine) {
  const Camera own = SceneStore::open(store_).camera();
  struct Case {
    const char* name;
    std::vector<std::string> options;
    std::vector<std::string> phrases;
  };
  const std::vector<Case> cases{
      {"unknown", {"--camera", "attic"}, {"--camera 'attic'", "no camera of that name", "overview, room-1"}},
      {"both",
       {"--camera", "corridor", "--look-from", text(own.origin), "--look-at", text(own.target)},
       {"--camera 'corridor'", "--look-from"}},
  };
  for (const Case& c : cases) {
    EXPECT_NE(render(c.name, 1, c.options), 0) << c.name;
    const std::string log = readFile(dir_ / (std::string(c.name) + ".log"));
    const size_t end = log.find('\n');
    const std::string first = log.substr(0, end), rest = end == std::string::npos ? "" : log.substr(end + 1);
    for (const std::string& phrase : c.phrases) EXPECT_NE(first.find(phrase), std::string::npos) << c.name << ": " << log;
    EXPECT_TRUE(rest.empty()) << c.name << ": " << log;
  }
}

}  // namespace
}  // namespace portico
