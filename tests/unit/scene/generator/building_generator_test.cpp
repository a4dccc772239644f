// The generated buildings: each preset reproduces the paper's statistics
// (Tables 1 and 2) within 10 %, is one connected graph of cells, has no
// degenerate triangles, and the same seed writes the same bytes.
#include "common/scene/generator/building_generator.h"
#include "common/scene/import/building_importer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <queue>
#include <string>
#include <vector>

#include "common/photometry/lamp_colour.h"
#include "common/scene/store/cell_geometry.h"
#include "common/scene/generator/furniture_library.h"
#include "common/scene/generator/room_furnisher.h"
#include "common/scene/store/scene_store.h"
#include "tests/unit/scene/scene_test_support.h"
#include "tests/unit/scene/standing_camera_checks.h"

namespace portico {
namespace {

using testing_support::readBytes;
using testing_support::TempDirectory;

struct PaperFigures {
  const char* preset;
  uint32_t floorsOption;   // --floors (tower only)
  double triangles, floors, rooms, lights, avgPerRoom, maxPerRoom;
};

// Table 1 and Table 2 of the paper (the tower per floor, Tower101 / 101).
const PaperFigures kPaper[] = {
    {"l-shape", 0, 0.34e6, 2, 27, 24, 12020, 68400},
    {"z-building", 0, 1.08e6, 1, 22, 15, 48816, 217429},
    {"octagon", 0, 5.25e6, 4, 232, 155, 22621, 451606},
    {"soda-hall", 0, 1.51e6, 7, 250, 2700, 6688, 44156},
    {"tower", 1, 10.6e6, 1, 176, 604, 60134, 172772},
};

void expectWithin10Percent(double measured, double paper, const std::string& what) {
  EXPECT_LE(std::abs(measured - paper), 0.1 * paper) << what << ": measured " << measured << ", paper " << paper;
}

class PresetStatistics : public ::testing::TestWithParam<PaperFigures> {};

TEST_P(PresetStatistics, MatchThePaperWithinTenPercent) {
  const PaperFigures& paper = GetParam();
  TempDirectory temp;
  const auto preset = findBuildingPreset(paper.preset, paper.floorsOption);
  ASSERT_TRUE(preset);
  generateBuilding(*preset, 1, temp / "store");
  const SceneStore store = SceneStore::open(temp / "store");
  uint64_t maxPerCell = 0;
  for (const CellInfo& cell : store.cells()) maxPerCell = std::max(maxPerCell, cell.triangleCount);
  const double triangles = double(store.totalTriangles());
  expectWithin10Percent(triangles, paper.triangles, "triangles");
  expectWithin10Percent(std::stod(store.meta().at("floors")), paper.floors, "floors");
  expectWithin10Percent(double(store.cells().size()), paper.rooms, "rooms (cells)");
  expectWithin10Percent(double(store.lights().size()), paper.lights, "lights");
  expectWithin10Percent(triangles / double(store.cells().size()), paper.avgPerRoom, "average triangles per room");
  expectWithin10Percent(double(maxPerCell), paper.maxPerRoom, "max triangles per room");
}

INSTANTIATE_TEST_SUITE_P(Paper, PresetStatistics, ::testing::ValuesIn(kPaper),
                         [](const auto& info) {
                           std::string name = info.param.preset;
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

TEST(BuildingGenerator, IsOneConnectedBuildingWithoutDegenerateTriangles) {
  TempDirectory temp;
  generateBuilding(*findBuildingPreset("l-shape", 0), 3, temp / "store");
  const SceneStore store = SceneStore::open(temp / "store");
  const size_t n = store.cells().size();
  std::vector<std::vector<uint32_t>> neighbours(n);
  for (const Portal& portal : store.portals()) {
    neighbours[portal.cellA].push_back(portal.cellB);
    neighbours[portal.cellB].push_back(portal.cellA);
  }
  std::vector<bool> seen(n, false);
  std::queue<uint32_t> open;
  open.push(store.camera().cell);
  seen[store.camera().cell] = true;
  while (!open.empty()) {
    const uint32_t cell = open.front();
    open.pop();
    for (uint32_t next : neighbours[cell])
      if (!seen[next]) seen[next] = true, open.push(next);
  }
  for (size_t c = 0; c < n; ++c) EXPECT_TRUE(seen[c]) << "cell " << store.cells()[c].name << " is unreachable";

  // Both floors have stairs between them: a portal joining cells on different floors.
  bool stairs = false;
  for (const Portal& portal : store.portals())
    stairs |= store.cells()[portal.cellA].bounds.lo.y != store.cells()[portal.cellB].bounds.lo.y &&
              store.cells()[portal.cellA].name.find("junction") != std::string::npos &&
              store.cells()[portal.cellB].name.find("junction") != std::string::npos;
  EXPECT_TRUE(stairs);

  for (const CellInfo& info : store.cells()) {
    const auto geometry = CellGeometry::load(store.cellPath(info.id), info.id, store.materials().size());
    const MeshView& mesh = geometry->mesh();
    uint32_t degenerate = 0, outside = 0;
    const Bounds3 grown(info.bounds.lo - Vec3(1e-3f), info.bounds.hi + Vec3(1e-3f));
    for (uint32_t t = 0; t < mesh.triangleCount; ++t) {
      Vec3 v[3];
      for (int k = 0; k < 3; ++k) {
        const uint32_t index = mesh.indices[3 * t + k];
        v[k] = Vec3(mesh.positions[3 * index], mesh.positions[3 * index + 1], mesh.positions[3 * index + 2]);
        outside += !grown.contains(v[k]);
      }
      degenerate += length(cross(v[1] - v[0], v[2] - v[0])) <= 0.0f;
    }
    EXPECT_EQ(degenerate, 0u) << info.name;
    EXPECT_EQ(outside, 0u) << info.name << ": vertices outside the cell";
  }
}

// Besides the overview (the default), every floor has a camera in a room's
// doorway and one in its corridor, each standing in its cell and looking
// across it; `--camera` finds them by these names.
TEST(BuildingGenerator, EveryFloorHasARoomAndACorridorCamera) {
  TempDirectory temp;
  generateBuilding(*findBuildingPreset("l-shape", 0), 3, temp / "store");
  const SceneStore store = SceneStore::open(temp / "store");
  EXPECT_EQ(store.camera().name, "overview");
  EXPECT_EQ(store.cells()[store.camera().cell].name, "sky");
  const uint32_t floors = uint32_t(std::stoul(store.meta().at("floors")));
  ASSERT_EQ(floors, 2u);
  EXPECT_EQ(store.cameras().size(), 1 + 2 * floors);
  for (uint32_t f = 0; f < floors; ++f) {
    const std::string floor = "floor" + std::to_string(f) + "-", cellFloor = "f" + std::to_string(f) + "-";
    const Camera* corridor = store.findCamera(floor + "corridor");
    ASSERT_NE(corridor, nullptr) << floor;
    EXPECT_EQ(store.cells()[corridor->cell].name, cellFloor + "corridor-0");
    testing_support::expectStandingCameraInItsCell(store, *corridor);
    const auto room = std::find_if(store.cameras().begin(), store.cameras().end(), [&](const Camera& camera) {
      return camera.name.rfind(floor + "room-", 0) == 0;
    });
    ASSERT_NE(room, store.cameras().end()) << floor;
    // Named after its cell: "floor1-room-0a2" stands in "f1-room-0a2".
    EXPECT_EQ(store.cells()[room->cell].name, cellFloor + room->name.substr(floor.size()));
    testing_support::expectStandingCameraInItsCell(store, *room);
    bool lit = false;
    for (const AreaLight& light : store.lights()) lit |= light.cell == room->cell;
    EXPECT_TRUE(lit) << room->name << " stands in a room without a light";
  }
}

TEST(BuildingGenerator, SameSeedSameBytesOtherSeedOtherFurniture) {
  TempDirectory temp;
  const BuildingPreset preset = *findBuildingPreset("l-shape", 0);
  generateBuilding(preset, 5, temp / "a");
  generateBuilding(preset, 5, temp / "b");
  generateBuilding(preset, 6, temp / "c");
  const SceneStore a = SceneStore::open(temp / "a"), c = SceneStore::open(temp / "c");
  bool anyDifferent = false;
  for (const CellInfo& cell : a.cells()) {
    const std::string file = "/cells/" + std::to_string(cell.id) + ".cell";
    EXPECT_EQ(readBytes(temp / ("a" + file)), readBytes(temp / ("b" + file))) << cell.name;
    anyDifferent |= readBytes(temp / ("a" + file)) != readBytes(temp / ("c" + file));
  }
  EXPECT_TRUE(anyDifferent);
}

// Ceiling panels given in lumens: each panel emits exactly that flux (179 x
// Y of its power), in the colour asked for, and the camera sees the radiance
// it emits (its triangles' material). By default the palette's radiance:
// 6 244 lm per m^2 of panel.
TEST(BuildingGenerator, PanelLumensGiveEveryCeilingPanelItsFlux) {
  TempDirectory temp;
  const BuildingPreset preset = *findBuildingPreset("l-shape", 0);
  generateBuilding(preset, 2, temp / "default");
  generateBuilding(preset, 2, temp / "lumens", PanelLighting{3000.0, 3000.0});
  const SceneStore byDefault = SceneStore::open(temp / "default"), byLumens = SceneStore::open(temp / "lumens");
  ASSERT_EQ(byDefault.lights().size(), byLumens.lights().size());
  ASSERT_GT(byLumens.lights().size(), 10u);
  double total = 0;
  const Vec3 warm = colourOfTemperature(3000);
  for (size_t i = 0; i < byLumens.lights().size(); ++i) {
    const AreaLight& light = byLumens.lights()[i];
    const AreaLight& standard = byDefault.lights()[i];
    EXPECT_EQ(standard.radiance, Vec3(12.0f, 11.0f, 9.5f));
    EXPECT_NEAR(lumensOfPower(standard.power()), 179.0 * kPi * (0.2126 * 12 + 0.7152 * 11 + 0.0722 * 9.5) * standard.area(),
                1e-3 * lumensOfPower(standard.power()));
    EXPECT_EQ(light.area(), standard.area());
    EXPECT_NEAR(lumensOfPower(light.power()), 3000.0, 3000.0 * 1e-5) << "panel " << i;
    EXPECT_NEAR(light.radiance.x / light.radiance.y, warm.x / warm.y, 1e-5);
    EXPECT_NEAR(light.radiance.z / light.radiance.y, warm.z / warm.y, 1e-5);
    total += lumensOfPower(light.power());
    // What the camera sees of it: a material emitting its radiance.
    bool shown = false;
    for (const Material& material : byLumens.materials()) shown |= material.emission == light.radiance;
    EXPECT_TRUE(shown) << "panel " << i;
  }
  EXPECT_NEAR(total, 3000.0 * double(byLumens.lights().size()), 1e-3 * total);
  EXPECT_THROW(generateBuilding(preset, 2, temp / "bad", PanelLighting{-5.0, {}}), std::invalid_argument);
}

TEST(BuildingGenerator, TowerFloorsScaleTheBuilding) {
  const auto one = findBuildingPreset("tower", 1), three = findBuildingPreset("tower", 3);
  ASSERT_TRUE(one && three);
  EXPECT_EQ(three->floors, 3u);
  EXPECT_EQ(three->cells, 3 * one->cells);
  EXPECT_EQ(three->triangles, 3 * one->triangles);
  EXPECT_FALSE(findBuildingPreset("pagoda", 0));
}

// The triangle counter that chooses a room's detail must agree with the
// meshes actually built, and every piece must stay on its footprint in
// every turn (furniture poking through a wall would leave its cell).
TEST(FurnitureLibrary, CountsMatchMeshesAndPiecesStayOnTheirFootprint) {
  furniture::Materials materials;
  for (int kind = 0; kind < furniture::kPieceKinds; ++kind)
    for (int turns = 0; turns < 4; ++turns)
      for (float detail : {0.25f, 1.0f, 3.7f}) {
        furniture::PieceSpec spec{furniture::Piece(kind), 1.3f, 0.9f, 1.2f, 17};
        MeshBuilder mesh;
        const furniture::Placement placement{Vec3(10.0f, 3.0f, 20.0f), turns};
        furniture::Emitter emitter(&mesh, spec.width, spec.depth, placement);
        furniture::emitPiece(emitter, spec, materials, detail);
        EXPECT_EQ(emitter.triangles(), mesh.triangleCount()) << "piece " << kind;
        CellContent content;
        mesh.moveInto(content);
        const float w = (turns & 1) ? spec.depth : spec.width, d = (turns & 1) ? spec.width : spec.depth;
        for (size_t v = 0; v < content.positions.size(); v += 3) {
          EXPECT_GE(content.positions[v], 10.0f - 0.02f) << "piece " << kind << " turns " << turns;
          EXPECT_LE(content.positions[v], 10.0f + w + 0.02f) << "piece " << kind << " turns " << turns;
          EXPECT_GE(content.positions[v + 1], 3.0f - 1e-4f);
          EXPECT_GE(content.positions[v + 2], 20.0f - 0.02f) << "piece " << kind << " turns " << turns;
          EXPECT_LE(content.positions[v + 2], 20.0f + d + 0.02f) << "piece " << kind << " turns " << turns;
        }
      }
}

TEST(RoomFurnisher, DetailMeetsTheTriangleBudget) {
  const furniture::FloorRect room{0.0f, 6.0f, 0.0f, 5.0f};
  for (auto style : {furniture::Style::Regular, furniture::Style::HandMade})
    for (uint64_t budget : {5000u, 40000u, 300000u}) {
      std::vector<furniture::PlacedPiece> pieces = furniture::arrangeRoom(room, 0.0f, {}, style, 9);
      ASSERT_FALSE(pieces.empty());
      const float detail = furniture::chooseDetail(pieces, budget);
      const double count = double(furniture::countTriangles(pieces, detail));
      EXPECT_NEAR(count, double(budget), 0.05 * double(budget)) << "budget " << budget;
    }
}

}  // namespace
}  // namespace portico

namespace portico {
namespace {

// `scene import --grid RG STORE OUT`: a generated building re-cut into voxel
// cells keeps its materials (hidden ceilings too), its light power and every
// triangle (each in at least one voxel).
TEST(BuildingGenerator, AGeneratedStoreRecutIntoVoxelCells) {
  TempDirectory temp;
  generateBuilding(*findBuildingPreset("l-shape", 0), 2, temp / "topological");
  ImportOptions options;
  options.gridResolution = 4;
  importBuilding({temp / "topological"}, temp / "voxels", options);
  const SceneStore topological = SceneStore::open(temp / "topological"), voxels = SceneStore::open(temp / "voxels");
  EXPECT_EQ(voxels.cells().size(), 64u);
  EXPECT_GE(voxels.totalTriangles(), topological.totalTriangles());
  ASSERT_EQ(voxels.materials().size(), topological.materials().size());
  for (size_t m = 0; m < voxels.materials().size(); ++m)
    EXPECT_EQ(voxels.materials()[m].hiddenFromCamera, topological.materials()[m].hiddenFromCamera);
  Vec3 before(0), after(0);
  for (const AreaLight& light : topological.lights()) before += light.power();
  for (const AreaLight& light : voxels.lights()) after += light.power();
  EXPECT_NEAR(after.x, before.x, 1e-3f * before.x);
  EXPECT_EQ(voxels.meta().at("cells"), "grid 4^3");
  // Without --grid a store is not imported again.
  EXPECT_THROW(importBuilding({temp / "topological"}, temp / "again", {}), std::runtime_error);
}

}  // namespace
}  // namespace portico
