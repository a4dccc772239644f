// placeWorkPlaneGrid on hand-made rooms written to real scene stores: the
// counts and positions worked out by hand, furniture, floor edges, rooms
// chosen by name, floor and cell, and the .pts file written from the grid.
#include "common/analysis/work_plane_grid.h"

#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <sstream>
#include <utility>

#include "common/analysis/pts_file_writer.h"
#include "tests/unit/analysis/analysis_test_scenes.h"
#include "tests/unit/scene/scene_test_support.h"

namespace portico {
namespace {

using testing_support::boxRoom;
using testing_support::TempDirectory;
using testing_support::TestCell;
using testing_support::writeTestStore;

// A 6 m x 4 m room, 3 m tall, its floor at y = floorY.

std::set<std::pair<float, float>> planPositions(const std::vector<Sensor>& sensors) {
  std::set<std::pair<float, float>> positions;
  for (const Sensor& s : sensors) positions.insert({s.position.x, s.position.z});
  return positions;
}

TEST(WorkPlaneGrid, BoxRoomGetsTheLatticeWorkedOutByHand) {
  TempDirectory dir;
  writeTestStore(dir / "store", {boxRoom("office", 0.0f)});
  const WorkPlaneGrid grid = placeWorkPlaneGrid(SceneStore::open(dir / "store"), {});
  // x: 0.5 .. 5.5 (6 m less 2 x 0.5 m inset, every 0.5 m: 11); z: 0.5 .. 3.5 (7).
  ASSERT_EQ(grid.sensors.size(), 77u);
  for (size_t k = 0; k < grid.sensors.size(); ++k) {
    const Sensor& s = grid.sensors[k];
    EXPECT_FLOAT_EQ(s.position.x, 0.5f + 0.5f * float(k % 11)) << k;
    EXPECT_FLOAT_EQ(s.position.z, 0.5f + 0.5f * float(k / 11)) << k;
    EXPECT_FLOAT_EQ(s.position.y, 0.8f);
    EXPECT_EQ(s.direction, Vec3(0, 1, 0));
    EXPECT_EQ(s.cell, 0);
    EXPECT_EQ(s.room, "office");
    EXPECT_EQ(s.sourceLine, 0u);
  }
  ASSERT_EQ(grid.rooms.size(), 1u);
  EXPECT_EQ(grid.rooms[0].sensors, 77u);
  EXPECT_NEAR(grid.rooms[0].floorArea, 24.0, 1e-4);
  EXPECT_FLOAT_EQ(grid.rooms[0].floorHeight, 0.0f);
}

TEST(WorkPlaneGrid, OptionsChangeHeightSpacingAndInset) {
  TempDirectory dir;
  writeTestStore(dir / "store", {boxRoom("office", 0.0f)});
  WorkPlaneGridOptions options;
  options.height = 0.75f;
  options.spacing = 0.6f;
  options.inset = 1.0f;
  const WorkPlaneGrid grid = placeWorkPlaneGrid(SceneStore::open(dir / "store"), options);
  // x span 6 - 2 = 4 m: floor(4 / 0.6) + 1 = 7 points, 3.6 m wide, centred: 1.2 .. 4.8.
  // z span 4 - 2 = 2 m: 4 points, 1.8 m wide: 1.1 .. 2.9.
  ASSERT_EQ(grid.sensors.size(), 28u);
  EXPECT_FLOAT_EQ(grid.sensors.front().position.x, 1.2f);
  EXPECT_FLOAT_EQ(grid.sensors.front().position.z, 1.1f);
  EXPECT_NEAR(grid.sensors.back().position.x, 4.8f, 1e-5);
  EXPECT_NEAR(grid.sensors.back().position.z, 2.9f, 1e-5);
  EXPECT_FLOAT_EQ(grid.sensors.front().position.y, 0.75f);
}

TEST(WorkPlaneGrid, PointsInsideFurnitureAreSkippedAndOverDesksKept) {
  TempDirectory dir;
  TestCell room = boxRoom("office", 0.0f);
  room.mesh.box(Vec3(1.8f, 0, 1.3f), Vec3(2.7f, 1.2f, 2.2f));   // a cupboard, taller than the plane
  room.mesh.level(3.8f, 0.8f, 4.7f, 1.7f, 0.72f, true);          // a desk top, lower than it
  room.mesh.level(3.8f, 0.8f, 4.7f, 1.7f, 0.70f, false);
  writeTestStore(dir / "store", {room});
  const WorkPlaneGrid grid = placeWorkPlaneGrid(SceneStore::open(dir / "store"), {});
  const auto positions = planPositions(grid.sensors);
  // The cupboard covers x 2.0, 2.5 and z 1.5, 2.0: 4 of the 77 points.
  EXPECT_EQ(grid.sensors.size(), 73u);
  for (float x : {2.0f, 2.5f})
    for (float z : {1.5f, 2.0f}) EXPECT_EQ(positions.count({x, z}), 0u) << x << " " << z;
  for (float x : {4.0f, 4.5f})
    for (float z : {1.0f, 1.5f}) EXPECT_EQ(positions.count({x, z}), 1u) << x << " " << z;
  EXPECT_EQ(positions.count({1.5f, 1.5f}), 1u);   // beside the cupboard: kept
}

TEST(WorkPlaneGrid, ShelvesAsTallAsWallsKeepTheInset) {
  TempDirectory dir;
  TestCell room = boxRoom("office", 0.0f);
  room.mesh.box(Vec3(2.9f, 0, 1.9f), Vec3(3.1f, 2.0f, 2.1f));   // a 2 m column of shelves in the middle
  writeTestStore(dir / "store", {room});
  const auto positions = planPositions(placeWorkPlaneGrid(SceneStore::open(dir / "store"), {}).sensors);
  // Within 0.5 m of its faces (cut 1.5 m up): x 2.5 .. 3.5 at z 2.0 and x 3.0 at z 1.5, 2.5 — and
  // (2.5, 1.5) etc. are 0.4^2 + 0.4^2 -> 0.566 m from its corner: kept.
  for (auto p : {std::pair{2.5f, 2.0f}, {3.0f, 2.0f}, {3.5f, 2.0f}, {3.0f, 1.5f}, {3.0f, 2.5f}})
    EXPECT_EQ(positions.count(p), 0u) << p.first << " " << p.second;
  EXPECT_EQ(positions.count({2.5f, 1.5f}), 1u);
  EXPECT_EQ(positions.size(), 77u - 5u);
}

TEST(WorkPlaneGrid, PointsKeepTheInsetFromTheFloorsEdges) {
  // An L-shaped floor (no walls): [0,6]x[0,2] and [0,2]x[2,6], a ceiling over it.
  TempDirectory dir;
  TestCell room{"hall", Bounds3(Vec3(0, 0, 0), Vec3(6, 3, 6)), {}};
  room.mesh.level(0, 0, 6, 2, 0, true);
  room.mesh.level(0, 2, 2, 6, 0, true);
  room.mesh.level(0, 0, 6, 2, 3, false);
  room.mesh.level(0, 2, 2, 6, 3, false);
  writeTestStore(dir / "store", {room});
  const WorkPlaneGrid grid = placeWorkPlaneGrid(SceneStore::open(dir / "store"), {});
  // Arm along x: z 0.5, 1.0, 1.5 and x 0.5 .. 5.5 (33); arm along z: x 0.5, 1.0, 1.5 and z 2.0 .. 5.5 (24).
  EXPECT_EQ(grid.sensors.size(), 57u);
  const auto positions = planPositions(grid.sensors);
  EXPECT_EQ(positions.count({5.5f, 1.5f}), 1u);
  EXPECT_EQ(positions.count({1.5f, 5.5f}), 1u);
  EXPECT_EQ(positions.count({2.0f, 2.0f}), 0u);   // 0.5 m from the inner corner diagonally: less than 0.5 from its edges
  EXPECT_EQ(positions.count({2.0f, 3.0f}), 0u);
  EXPECT_NEAR(grid.rooms.at(0).floorArea, 20.0, 1e-4);
  const std::optional<RoomFloor> floor = findRoomFloor(SceneStore::open(dir / "store"), 0);
  ASSERT_TRUE(floor.has_value());
  EXPECT_NEAR(floor->area, 20.0, 1e-4);
  EXPECT_FLOAT_EQ(floor->height, 0.0f);
}

TEST(WorkPlaneGrid, CellsOpenToTheSkyAreNoRooms) {
  TempDirectory dir;
  TestCell yard{"yard", Bounds3(Vec3(10, 0, 0), Vec3(16, 3, 4)), {}};
  yard.mesh.level(10, 0, 16, 4, 0, true);   // ground, nothing above
  writeTestStore(dir / "store", {boxRoom("office", 0.0f), yard});
  const WorkPlaneGrid grid = placeWorkPlaneGrid(SceneStore::open(dir / "store"), {});
  ASSERT_EQ(grid.rooms.size(), 1u);
  EXPECT_EQ(grid.rooms[0].name, "office");
  EXPECT_EQ(grid.sensors.size(), 77u);
}

TEST(WorkPlaneGrid, PointsOverALowPitchedRoofAreOutsideTheBuilding) {
  // A 6 x 4 m attic whose roof, 10 cm thick, rises from 0.3 m (inner face)
  // at z = 0 to 3.3 m at z = 4: y = 0.3 + 0.75 z inside, 0.4 + 0.75 z outside.
  TempDirectory dir;
  TestCell attic{"attic", Bounds3(Vec3(0, 0, 0), Vec3(6, 3.5f, 4)), {}};
  attic.mesh.level(0, 0, 6, 4, 0, true);
  const auto roof = [&](float lift, bool down) {
    const Vec3 a(0, 0.3f + lift, 0), b(6, 0.3f + lift, 0), c(6, 3.3f + lift, 4), d(0, 3.3f + lift, 4);
    if (down) attic.mesh.quad(a, b, c, d); else attic.mesh.quad(a, d, c, b);
  };
  roof(0.0f, true);
  roof(0.1f, false);
  attic.mesh.wallX(0, 0, 4, 0, 3.5f);
  attic.mesh.wallX(6, 0, 4, 0, 3.5f);
  attic.mesh.wallZ(4, 0, 6, 0, 3.5f);
  attic.mesh.wallZ(0, 0, 6, 0, 0.3f);
  writeTestStore(dir / "store", {attic});
  const WorkPlaneGrid grid = placeWorkPlaneGrid(SceneStore::open(dir / "store"), {});
  // Rows z = 0.5 .. 3.5. At z = 0.5 the roof's outer face is 0.775 m up,
  // under the 0.8 m plane: those points are outdoors. z = 1.0 .. 2.0: the
  // roof within 1 m above the plane, or within 0.5 m of its 1.5 m cut. Kept:
  // z = 2.5, 3.0, 3.5, 11 points each.
  const auto positions = planPositions(grid.sensors);
  EXPECT_EQ(grid.sensors.size(), 33u);
  for (float x : {0.5f, 3.0f, 5.5f}) {
    EXPECT_EQ(positions.count({x, 0.5f}), 0u) << x;
    EXPECT_EQ(positions.count({x, 2.5f}), 1u) << x;
  }
}

TEST(WorkPlaneGrid, PointsUnderAnOpeningKeepTheirPlaceOnlyUnderAnIndoorCell) {
  // A hall 6 x 4 x 3 m with a ceiling over x < 3.25 only; over the rest a portal
  // into the cell above: a gallery (indoors), or the sky (an outdoor cell).
  const auto gridWithAbove = [](const std::string& above) {
    TempDirectory dir;
    TestCell hall{"hall", Bounds3(Vec3(0, 0, 0), Vec3(6, 3, 4)), {}};
    hall.mesh.level(0, 0, 6, 4, 0, true);
    hall.mesh.level(0, 0, 3.25f, 4, 3, false);
    hall.mesh.wallX(0, 0, 4, 0, 3);
    hall.mesh.wallX(6, 0, 4, 0, 3);
    hall.mesh.wallZ(0, 0, 6, 0, 3);
    hall.mesh.wallZ(4, 0, 6, 0, 3);
    TestCell upper{above, Bounds3(Vec3(0, 3, 0), Vec3(6, 6, 4)), {}};
    upper.mesh.level(0, 0, 3.25f, 4, 3, true);
    writeTestStore(dir / "store", {hall, upper},
                   {{0, 1, {Vec3(3.25f, 3, 0), Vec3(6, 3, 0), Vec3(6, 3, 4), Vec3(3.25f, 3, 4)}}});
    WorkPlaneGridOptions options;
    options.cells = {0};
    return placeWorkPlaneGrid(SceneStore::open(dir / "store"), options);
  };
  // x 0.5 .. 5.5 (11) by z 0.5 .. 3.5 (7); under the ceiling x <= 3.0 (6 columns).
  EXPECT_EQ(gridWithAbove("gallery").sensors.size(), 77u);
  const WorkPlaneGrid open = gridWithAbove("outside-1");
  EXPECT_EQ(open.sensors.size(), 42u);
  for (const Sensor& s : open.sensors) EXPECT_LT(s.position.x, 3.25f);
}

TEST(WorkPlaneGrid, RoomsAreChosenByNameFloorAndCell) {
  TempDirectory dir;
  TestCell upstairs = boxRoom("f1-office", 3.0f);
  writeTestStore(dir / "store", {boxRoom("f0-office", 0.0f), upstairs, boxRoom("f0-store", 0.0f)});
  const SceneStore store = SceneStore::open(dir / "store");
  const auto roomsOf = [&](const WorkPlaneGridOptions& options) {
    std::vector<std::string> names;
    for (const WorkPlaneRoom& room : placeWorkPlaneGrid(store, options).rooms) names.push_back(room.name);
    return names;
  };
  using Names = std::vector<std::string>;
  EXPECT_EQ(roomsOf({}), (Names{"f0-office", "f1-office", "f0-store"}));
  WorkPlaneGridOptions byName;
  byName.roomNames = {"*-office"};
  EXPECT_EQ(roomsOf(byName), (Names{"f0-office", "f1-office"}));
  WorkPlaneGridOptions byFloor;
  byFloor.floors = {1};
  EXPECT_EQ(roomsOf(byFloor), (Names{"f1-office"}));
  const WorkPlaneGrid upper = placeWorkPlaneGrid(store, byFloor);
  EXPECT_FLOAT_EQ(upper.sensors.front().position.y, 3.8f);
  EXPECT_EQ(upper.rooms.front().floor, 1u);
  WorkPlaneGridOptions byCell;
  byCell.cells = {2};
  EXPECT_EQ(roomsOf(byCell), (Names{"f0-store"}));
  WorkPlaneGridOptions both;   // each list narrows
  both.roomNames = {"*-office"};
  both.floors = {0};
  EXPECT_EQ(roomsOf(both), (Names{"f0-office"}));
}

TEST(WorkPlaneGrid, BadOptionsAreOneLineErrors) {
  TempDirectory dir;
  writeTestStore(dir / "store", {boxRoom("office", 0.0f)});
  const SceneStore store = SceneStore::open(dir / "store");
  const auto errorOf = [&](const WorkPlaneGridOptions& options) -> std::string {
    try {
      placeWorkPlaneGrid(store, options);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  };
  WorkPlaneGridOptions options;
  options.spacing = 0;
  EXPECT_EQ(errorOf(options), "--grid-spacing: 0 is not a positive number of metres");
  options = {};
  options.cells = {5};
  EXPECT_NE(errorOf(options).find("--grid-cells: scene store"), std::string::npos);
  options = {};
  options.floors = {2};
  EXPECT_NE(errorOf(options).find("has no floor 2"), std::string::npos);
}

TEST(PtsFile, WrittenGridReadsBackToTheSameNumbers) {
  TempDirectory dir;
  writeTestStore(dir / "store", {boxRoom("office", 0.0f)});
  WorkPlaneGridOptions options;
  options.spacing = 0.3f;   // 0.3 steps are not exact in binary: the text must still read back exactly
  const WorkPlaneGrid grid = placeWorkPlaneGrid(SceneStore::open(dir / "store"), options);
  writePtsFile(dir / "grid.pts", grid.sensors);
  std::ifstream in(dir / "grid.pts");
  std::string line;
  size_t count = 0;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    float x, y, z, dx, dy, dz;
    ASSERT_TRUE(fields >> x >> y >> z >> dx >> dy >> dz) << line;
    const Sensor& s = grid.sensors.at(count++);
    EXPECT_EQ(Vec3(x, y, z), s.position) << line;
    EXPECT_EQ(Vec3(dx, dy, dz), Vec3(0, 1, 0)) << line;
  }
  EXPECT_EQ(count, grid.sensors.size());
  EXPECT_GT(count, 0u);
}

}  // namespace
}  // namespace portico
