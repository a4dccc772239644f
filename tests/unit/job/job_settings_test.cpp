#include "common/job/job_settings.h"

#include <capnp/message.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <limits>
#include <string>

#include "common/job/sun_time.h"
#include "common/net/job_spec_wire.h"
#include "common/scene/generator/demo_generator.h"
#include "common/scene/import/building_importer.h"
#include "common/scene/store/scene_store.h"
#include "coordinator/job_limits.h"
#include "coordinator/job_planner.h"
#include "tests/support/temp_directory.h"

namespace portico {
namespace {

namespace fs = std::filesystem;

// two_rooms as rooms (grid 0) or as voxel cells, imported once per process.
const SceneStore& twoRooms(uint32_t grid) {
  static std::map<uint32_t, SceneStore> stores;
  if (auto it = stores.find(grid); it != stores.end()) return it->second;
  const fs::path store = testing_support::tempPath("job-settings-" + std::to_string(grid), false);
  ImportOptions options;
  options.gridResolution = grid;
  importBuilding({std::string(PORTICO_REFERENCE_DIR) + "/two_rooms/scene.json"}, store.string(), options);
  return stores.emplace(grid, SceneStore::open(store.string())).first->second;
}

TEST(JobSettings, EveryAutomaticValueIsResolvedOnceFromTheScene) {
  const SceneStore& rooms = twoRooms(0);
  const JobSettings resolved = resolveJobSettings(JobSettings{}, rooms);
  EXPECT_EQ(resolved.width, rooms.camera().width);
  EXPECT_EQ(resolved.height, rooms.camera().height);
  EXPECT_EQ(resolved.lightHops, 2);   // room cells
  EXPECT_EQ(resolved.accel, "auto");        // the fastest photon pass (docs/pipeline-benchmark.md)
  EXPECT_EQ(resolved.renderAccel, "bvh");
  JobSettings grid;
  grid.accel = "grid";
  EXPECT_EQ(resolveJobSettings(grid, rooms).renderAccel, "bvh");
  EXPECT_EQ(resolveJobSettings(resolved, rooms), resolved);   // nothing left to resolve
  EXPECT_NO_THROW(validateJobSettings(resolved, rooms));

  EXPECT_EQ(resolveJobSettings(JobSettings{}, twoRooms(2)).lightHops, -1);   // voxel cells: every light
  JobSettings chosen;
  chosen.accel = "kd:sah";
  chosen.lightHops = 0;
  chosen.width = 32;
  chosen.height = 16;
  const JobSettings kept = resolveJobSettings(chosen, rooms);
  EXPECT_EQ(kept.renderAccel, "kd:sah");
  EXPECT_EQ(kept.lightHops, 0);
  EXPECT_EQ(kept.width, 32u);
  EXPECT_EQ(kept.height, 16u);
}

TEST(JobSettings, TheDefaultPhotonCountFollowsTheLightsBetweenAFloorAndACap) {
  EXPECT_EQ(defaultPhotonCount(1), kMinDefaultPhotons);
  EXPECT_EQ(defaultPhotonCount(0), kMinDefaultPhotons);
  EXPECT_EQ(defaultPhotonCount(100), 100 * kDefaultPhotonsPerLight);
  EXPECT_EQ(defaultPhotonCount(61000), kMaxDefaultPhotons);
  // two_rooms: one light, in one of its three cells: the floor.
  const SceneStore& rooms = twoRooms(0);
  EXPECT_EQ(resolveJobSettings(JobSettings{}, rooms).photons, kMinDefaultPhotons);
  JobSettings chosen;
  chosen.photons = 12345;
  EXPECT_EQ(resolveJobSettings(chosen, rooms).photons, 12345u);
  JobSettings cells;
  cells.aov = JobSettings::Aov::Cells;   // no photon pass: no photons
  EXPECT_EQ(resolveJobSettings(cells, rooms).photons, 0u);
}

TEST(JobSettings, ASubmitThatLeavesValuesOutGetsTheDefaults) {
  capnp::MallocMessageBuilder message;
  auto spec = message.initRoot<wire::JobSpec>();
  spec.setPhotons(10);
  spec.setSpp(1);
  spec.setPhotonRadius(0.5f);
  const JobSettings resolved = resolveJobSettings(jobSettingsFromWire(spec.asReader()), twoRooms(0));
  const JobSettings defaults;
  EXPECT_EQ(resolved.photonK, defaults.photonK);
  EXPECT_EQ(resolved.exposure, defaults.exposure);
  EXPECT_EQ(resolved.accel, defaults.accel);
  EXPECT_EQ(resolved.renderAccel, "bvh");
  EXPECT_EQ(resolved.lightHops, 2);   // the wire's own default
  EXPECT_NO_THROW(validateJobSettings(resolved, twoRooms(0)));
}

TEST(JobSettings, RenderPassesAreOneUnlessATargetOrTimeLimitAsksAndBadBoundsAreRefused) {
  const SceneStore& rooms = twoRooms(0);
  EXPECT_EQ(resolveJobSettings(JobSettings{}, rooms).maxPasses, 1u);
  JobSettings target;
  target.targetError = 0.02;
  EXPECT_EQ(resolveJobSettings(target, rooms).maxPasses, kProgressiveMaxPasses);
  JobSettings limit;
  limit.timeLimitSeconds = 3;
  limit.maxPasses = 5;
  EXPECT_EQ(resolveJobSettings(limit, rooms).maxPasses, 5u);
  EXPECT_NO_THROW(validateJobSettings(resolveJobSettings(limit, rooms), rooms));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (double bad : {0.0, -0.01, nan, 1.5}) {
    JobSettings settings;
    settings.targetError = bad;
    EXPECT_THROW(validateJobSettings(resolveJobSettings(settings, rooms), rooms), std::invalid_argument) << bad;
  }
  for (double bad : {0.0, -2.0, nan, std::numeric_limits<double>::infinity()}) {
    JobSettings settings;
    settings.timeLimitSeconds = bad;
    try {
      validateJobSettings(resolveJobSettings(settings, rooms), rooms);
      ADD_FAILURE() << bad << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("time limit"), std::string::npos) << e.what();
    }
  }
  JobSettings many;
  many.maxPasses = limits::kMaxPasses + 1;
  EXPECT_THROW(validateJobSettings(resolveJobSettings(many, rooms), rooms), std::invalid_argument);
}

TEST(JobSettings, TheWireFormKeepsEveryField) {
  JobSettings settings;
  settings.store = "/stores/a";
  settings.output = "/images/a.exr";
  settings.accel = "kd:sah";
  settings.renderAccel = "embree";
  settings.photons = 123456;
  settings.spp = 3;
  settings.gather = 7;
  settings.seed = 99;
  settings.width = 640;
  settings.height = 480;
  settings.lightSamples = 5;
  settings.lightHops = -1;
  settings.photonK = 17;
  settings.photonRadius = 0.25f;
  settings.exposure = 2.5f;
  settings.irradiance = JobSettings::Irradiance::Knn;
  settings.aov = JobSettings::Aov::Portals;
  settings.camera = JobCamera{Vec3(1, 2, 3), Vec3(4, 5, 6), Vec3(0, 0, 1), 35.5f, 7};
  settings.targetError = 0.015;
  settings.timeLimitSeconds = 12.5;
  settings.maxPasses = 9;
  settings.cameraName = "floor2-corridor";
  settings.daylight.sky = DaylightSettings::Sky::Preetham;
  settings.daylight.sun = true;
  settings.daylight.turbidity = 4.5f;
  // A sun by time: a place of its own, the site's north.
  settings.daylight.sunTime = SunTime{1782045000, 49.1003, -8.4366, std::nullopt};
  settings.luminance = LuminanceImage{true, 250.0, 3, 6};
  capnp::MallocMessageBuilder message;
  toWire(settings, message.initRoot<wire::JobSpec>());
  EXPECT_EQ(jobSettingsFromWire(message.getRoot<wire::JobSpec>().asReader()), settings);
  settings.daylight.sunTime = SunTime{-5, std::nullopt, std::nullopt, 270.0};
  capnp::MallocMessageBuilder other;
  toWire(settings, other.initRoot<wire::JobSpec>());
  EXPECT_EQ(jobSettingsFromWire(other.getRoot<wire::JobSpec>().asReader()), settings);
}

// The refusal resolveJobSettings gives ("" for none).
std::string resolveRefusal(const JobSettings& settings, const SceneStore& scene) {
  try {
    resolveJobSettings(settings, scene);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

// `--sun-time`: resolved once into the angles `--sun` gives, the time cleared.
TEST(JobSettings, ASunTimeIsResolvedIntoTheSunsAngles) {
  const SceneStore& rooms = twoRooms(0);   // no site
  JobSettings settings;
  settings.daylight.sky = DaylightSettings::Sky::Preetham;
  settings.daylight.sun = true;
  settings.daylight.sunTime = SunTime{1782045000, 49.1003, 8.4366, 0.0};
  const JobSettings resolved = resolveJobSettings(settings, rooms);
  EXPECT_FALSE(resolved.daylight.sunTime);
  EXPECT_EQ(resolved.daylight, resolveSunTime(settings.daylight, std::nullopt, rooms.directory()));
  EXPECT_NEAR(resolved.daylight.sunElevationDegrees, 61.6, 0.5);   // Karlsruhe, June, an hour after noon
  EXPECT_EQ(resolveJobSettings(resolved, rooms), resolved);
  settings.daylight.sunTime->latitudeDegrees.reset();
  settings.daylight.sunTime->longitudeDegrees.reset();
  const std::string refusal = resolveRefusal(settings, rooms);
  EXPECT_NE(refusal.find("no place to see the sun from"), std::string::npos) << refusal;
}

// `--camera NAME`: the store camera as stored (its cell, its image size),
// the name cleared once resolved; an unknown name or a name beside a camera
// of the job's own is refused, naming it.
TEST(JobSettings, ANamedCameraIsResolvedIntoTheJobsCamera) {
  const fs::path directory = fs::temp_directory_path() / ("portico-job-settings-demo-" + std::to_string(getpid()));
  generateDemoBuilding(directory.string(), 3);
  const SceneStore demo = SceneStore::open(directory.string());
  fs::remove_all(directory);
  const Camera& dark = *demo.findCamera("dark-room");
  JobSettings settings;
  settings.cameraName = "dark-room";
  const JobSettings resolved = resolveJobSettings(settings, demo);
  EXPECT_EQ(resolved.camera, (JobCamera{dark.origin, dark.target, dark.up, dark.fovYDegrees, kDemoDarkRoomCell}));
  EXPECT_EQ(resolved.cameraName, "");
  EXPECT_EQ(resolved.width, dark.width);
  EXPECT_EQ(resolved.height, dark.height);
  EXPECT_EQ(resolveJobSettings(resolved, demo), resolved);
  settings.cameraName = demo.camera().name;   // the default by name: the default
  EXPECT_EQ(resolveJobSettings(settings, demo), resolveJobSettings(JobSettings{}, demo));

  settings.cameraName = "attic";
  std::string refusal = resolveRefusal(settings, demo);
  EXPECT_NE(refusal.find("--camera 'attic'"), std::string::npos) << refusal;
  EXPECT_NE(refusal.find("overview, room-1, room-2"), std::string::npos) << refusal;
  EXPECT_NE(refusal.find("and 2 more"), std::string::npos) << refusal;   // 8 cameras, 6 listed
  EXPECT_EQ(refusal.find('\n'), std::string::npos) << refusal;
  settings.cameraName = "corridor";
  settings.camera = JobCamera{dark.origin, dark.target};
  refusal = resolveRefusal(settings, demo);
  EXPECT_NE(refusal.find("--camera 'corridor' and --look-from"), std::string::npos) << refusal;
}

TEST(JobSettings, TheCameraIsTheStoresUnlessChosenAndAChosenOneIsInTheCellOfItsEye) {
  const SceneStore& rooms = twoRooms(0);
  const Camera& own = rooms.camera();
  const JobCamera stores = *resolveJobSettings(JobSettings{}, rooms).camera;
  EXPECT_EQ(stores, (JobCamera{own.origin, own.target, own.up, own.fovYDegrees, own.cell}));

  // An eye in another cell: up and fov come from the store's camera.
  uint32_t other = own.cell == 0 ? 1 : 0;
  JobSettings chosen;
  chosen.camera = JobCamera{rooms.cells()[other].bounds.center(), own.target};
  const JobSettings resolved = resolveJobSettings(chosen, rooms);
  EXPECT_EQ(resolved.camera->cell, rooms.locateCell(chosen.camera->lookFrom).value());
  EXPECT_EQ(resolved.camera->up, own.up);
  EXPECT_EQ(resolved.camera->fovYDegrees, own.fovYDegrees);
  EXPECT_EQ(resolveJobSettings(resolved, rooms), resolved);

  const auto refusal = [&](JobCamera camera) -> std::string {
    JobSettings settings;
    settings.camera = camera;
    try {
      resolveJobSettings(settings, rooms);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(refusal({Vec3(1e6f), own.target}).find("--look-from"), std::string::npos);
  EXPECT_NE(refusal({own.origin, own.origin}).find("--look-at"), std::string::npos);
  EXPECT_NE(refusal({own.origin, own.target, Vec3(0), 180.0f}).find("--fov"), std::string::npos);
  EXPECT_NE(refusal({own.origin, own.target, own.target - own.origin}).find("--up"), std::string::npos);
  EXPECT_NE(refusal({Vec3(std::nanf("")), own.target}).find("--look-from"), std::string::npos);
}

}  // namespace
}  // namespace portico
