// The building importer: the reference scenes imported as they are (given
// cells, one cell, voxel cells), mesh-only imports, and the one-line errors
// of broken inputs (which must leave no store behind).
#include "common/scene/import/building_importer.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <stdexcept>

#include "common/photometry/lamp_colour.h"
#include "common/scene/store/cell_geometry.h"
#include "common/scene/import/mesh_loader.h"
#include "common/scene/import/quad_light.h"
#include "common/scene/store/scene_store.h"
#include "common/triangle_box_overlap.h"
#include "tests/unit/scene/scene_test_support.h"

namespace portico {
namespace {

namespace fs = std::filesystem;
using testing_support::TempDirectory;

const fs::path kReferenceDirectory(PORTICO_REFERENCE_DIR);

#define REQUIRE_REFERENCE_SCENE(name)                                                          \
  if (!fs::exists(kReferenceDirectory / (name) / "scene.json"))                                \
    GTEST_SKIP() << "reference scene " << (kReferenceDirectory / (name)).string() << " is absent";

std::string referenceJson(const std::string& name) { return (kReferenceDirectory / name / "scene.json").string(); }

template <typename Action>
std::string errorOf(Action&& action) {
  try {
    action();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

void writeText(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

std::unique_ptr<CellGeometry> loadCell(const SceneStore& store, uint32_t cell) {
  return CellGeometry::load(store.cellPath(cell), cell, store.materials().size());
}

using TriangleKey = std::array<float, 9>;

TriangleKey keyOf(const Vec3& a, const Vec3& b, const Vec3& c) {
  return {a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z};
}

// Every triangle of every cell file lies within its cell's bounds.
void expectTrianglesInsideCells(const SceneStore& store) {
  for (const CellInfo& info : store.cells()) {
    const auto cell = loadCell(store, info.id);
    const MeshView& mesh = cell->mesh();
    const float tolerance = 1e-5f * std::max(1.0f, maxComponent(info.bounds.diagonal()));
    const Bounds3 grown(info.bounds.lo - Vec3(tolerance), info.bounds.hi + Vec3(tolerance));
    for (uint32_t t = 0; t < mesh.triangleCount; ++t) {
      Vec3 a, b, c;
      mesh.triangle(t, a, b, c);
      EXPECT_TRUE(grown.contains(a) && grown.contains(b) && grown.contains(c))
          << "cell " << info.name << " triangle " << t;
    }
  }
}

Vec3 normalOfTriangleAt(const SceneStore& store, uint32_t cellId, const std::function<bool(const Vec3&)>& select) {
  const auto cell = loadCell(store, cellId);
  const MeshView& mesh = cell->mesh();
  for (uint32_t t = 0; t < mesh.triangleCount; ++t) {
    Vec3 a, b, c;
    mesh.triangle(t, a, b, c);
    if (select((a + b + c) * (1.0f / 3.0f))) return normalize(mesh.geometricNormal(t));
  }
  ADD_FAILURE() << "no triangle selected";
  return Vec3(0);
}

TEST(BuildingImport, CornellClosedIsOneCellWithItsLightAndCamera) {
  REQUIRE_REFERENCE_SCENE("cornell_closed");
  TempDirectory temp;
  importBuilding({referenceJson("cornell_closed")}, temp / "store");
  const SceneStore store = SceneStore::open(temp / "store");

  ASSERT_EQ(store.cells().size(), 1u);
  EXPECT_TRUE(store.portals().empty());
  EXPECT_EQ(store.totalTriangles(), 34u);
  EXPECT_EQ(store.meta().at("generator"), "import");
  EXPECT_NE(store.meta().at("source").find("scene.json"), std::string::npos);
  // Scene bounds x [-1, 1], y [0, 2], z [-1, 2], padded by 1 mm.
  const Bounds3& bounds = store.cells()[0].bounds;
  EXPECT_NEAR(bounds.lo.x, -1.001f, 1e-5f);
  EXPECT_NEAR(bounds.hi.y, 2.001f, 1e-5f);
  EXPECT_NEAR(bounds.hi.z, 2.001f, 1e-5f);
  // White, red, green, and the light.
  EXPECT_EQ(store.materials().size(), 4u);

  ASSERT_EQ(store.lights().size(), 1u);
  const AreaLight& light = store.lights()[0];
  EXPECT_EQ(light.cell, 0u);
  const float power = kPi * 0.16f * 15.0f;
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(light.power()[c], power, 1e-3f * power);
  EXPECT_NEAR(light.normal().y, -1.0f, 1e-6f);
  EXPECT_NEAR(light.center().x, 0.0f, 1e-6f);
  EXPECT_NEAR(light.center().y, 1.999f, 1e-6f);
  EXPECT_NEAR(light.center().z, 0.0f, 1e-6f);

  const Camera& camera = store.camera();
  EXPECT_EQ(camera.origin, Vec3(0.0f, 1.0f, 1.95f));
  EXPECT_EQ(camera.target, Vec3(0.0f, 1.1f, -1.0f));
  EXPECT_EQ(camera.up, Vec3(0.0f, 1.0f, 0.0f));
  EXPECT_EQ(camera.fovYDegrees, 70.0f);
  EXPECT_EQ(camera.width, 256u);
  EXPECT_EQ(camera.height, 256u);
  EXPECT_EQ(camera.cell, 0u);
  expectTrianglesInsideCells(store);

  // Winding is kept: the floor faces up, the ceiling and the light face down.
  EXPECT_NEAR(normalOfTriangleAt(store, 0, [](const Vec3& p) { return p.y == 0.0f; }).y, 1.0f, 1e-6f);
  EXPECT_NEAR(normalOfTriangleAt(store, 0, [](const Vec3& p) { return p.y == 2.0f; }).y, -1.0f, 1e-6f);
  EXPECT_NEAR(normalOfTriangleAt(store, 0, [](const Vec3& p) { return std::abs(p.y - 1.999f) < 1e-5f; }).y, -1.0f,
              1e-6f);
}

TEST(BuildingImport, TwoRoomsKeepsItsCellsPortalsLightAndCamera) {
  REQUIRE_REFERENCE_SCENE("two_rooms");
  TempDirectory temp;
  importBuilding({referenceJson("two_rooms")}, temp / "store");
  const SceneStore store = SceneStore::open(temp / "store");

  ASSERT_EQ(store.cells().size(), 3u);
  std::map<std::string, uint32_t> ids;
  for (const CellInfo& cell : store.cells()) ids[cell.name] = cell.id;
  ASSERT_EQ(ids.size(), 3u);
  ASSERT_TRUE(ids.count("roomA") && ids.count("door") && ids.count("roomB"));
  EXPECT_EQ(store.totalTriangles(), 98u);
  EXPECT_EQ(store.cells()[ids["door"]].triangleCount, 8u);
  EXPECT_EQ(store.cells()[ids["roomA"]].bounds.lo, Vec3(-4.1f, 0.0f, -1.5f));

  ASSERT_EQ(store.portals().size(), 2u);
  std::set<std::set<uint32_t>> joined;
  for (const Portal& portal : store.portals()) {
    joined.insert({portal.cellA, portal.cellB});
    EXPECT_EQ(portal.polygon.size(), 4u);
  }
  const std::set<std::set<uint32_t>> expected{{ids["roomA"], ids["door"]}, {ids["door"], ids["roomB"]}};
  EXPECT_EQ(joined, expected);

  ASSERT_EQ(store.lights().size(), 1u);
  EXPECT_EQ(store.lights()[0].cell, ids["roomA"]);
  const float power = kPi * 0.36f * 20.0f;
  EXPECT_NEAR(store.lights()[0].power().x, power, 1e-3f * power);
  EXPECT_NEAR(store.lights()[0].normal().y, -1.0f, 1e-6f);
  EXPECT_EQ(store.camera().cell, ids["roomB"]);
  EXPECT_EQ(store.camera().origin, Vec3(4.0f, 1.6f, 1.4f));
  EXPECT_EQ(store.camera().fovYDegrees, 60.0f);
  expectTrianglesInsideCells(store);
}

// Every input triangle of two_rooms, from the same loader the importer uses.
std::vector<TriangleKey> twoRoomsInputTriangles() {
  std::vector<TriangleKey> triangles;
  for (const auto& entry : fs::directory_iterator(kReferenceDirectory / "two_rooms")) {
    if (entry.path().extension() != ".obj") continue;
    const LoadedMeshFile mesh = loadMeshFile(entry.path().string());
    for (const MeshFilePart& part : mesh.parts)
      for (size_t t = 0; t < part.triangleCount(); ++t) {
        auto vertex = [&](int corner) {
          const size_t i = part.indices[3 * t + corner];
          return Vec3(part.positions[3 * i], part.positions[3 * i + 1], part.positions[3 * i + 2]);
        };
        triangles.push_back(keyOf(vertex(0), vertex(1), vertex(2)));
      }
  }
  return triangles;
}

TEST(BuildingImportGrid, TwoRoomsInFourCubedVoxels) {
  REQUIRE_REFERENCE_SCENE("two_rooms");
  TempDirectory temp;
  ImportOptions options;
  options.gridResolution = 4;
  importBuilding({referenceJson("two_rooms")}, temp / "store", options);
  const SceneStore store = SceneStore::open(temp / "store");

  ASSERT_EQ(store.cells().size(), 64u);
  EXPECT_EQ(store.portals().size(), 3u * 4 * 4 * 3);
  EXPECT_EQ(store.cells()[1 + 4 * (2 + 4 * 3)].name, "voxel-1-2-3");
  Bounds3 grid;
  for (const CellInfo& cell : store.cells()) grid.extend(cell.bounds);
  // The padded scene bounds: x [-4.1, 4.1], y [0, 2.5], z [-1.5, 1.5] plus 1 mm.
  EXPECT_NEAR(grid.lo.x, -4.101f, 1e-5f);
  EXPECT_NEAR(grid.hi.y, 2.501f, 1e-5f);

  // Portals: between face neighbours, exactly on their shared face.
  for (const Portal& portal : store.portals()) {
    const Bounds3& a = store.cells()[portal.cellA].bounds;
    const Bounds3& b = store.cells()[portal.cellB].bounds;
    int sharedAxis = -1;
    for (int axis = 0; axis < 3; ++axis)
      if (a.hi[axis] == b.lo[axis]) sharedAxis = axis;
    ASSERT_GE(sharedAxis, 0) << "portal " << portal.id;
    ASSERT_EQ(portal.polygon.size(), 4u);
    for (const Vec3& p : portal.polygon) {
      EXPECT_EQ(p[sharedAxis], a.hi[sharedAxis]);
      EXPECT_TRUE(a.contains(p) && b.contains(p));
    }
  }

  // Triangles: in every voxel the conservative test says they touch (and so
  // in at least one), and nowhere else.
  std::vector<std::set<TriangleKey>> cellTriangles(store.cells().size());
  for (const CellInfo& info : store.cells()) {
    const auto cell = loadCell(store, info.id);
    for (uint32_t t = 0; t < cell->mesh().triangleCount; ++t) {
      Vec3 a, b, c;
      cell->mesh().triangle(t, a, b, c);
      cellTriangles[info.id].insert(keyOf(a, b, c));
    }
  }
  const float tolerance = 1e-5f * maxComponent(grid.diagonal());
  const std::vector<TriangleKey> input = twoRoomsInputTriangles();
  ASSERT_EQ(input.size(), 98u);
  size_t references = 0;
  for (const TriangleKey& key : input) {
    const Vec3 a(key[0], key[1], key[2]), b(key[3], key[4], key[5]), c(key[6], key[7], key[8]);
    size_t cells = 0;
    for (const CellInfo& info : store.cells()) {
      const bool touches = triangleOverlapsBox(a, b, c, info.bounds, tolerance);
      EXPECT_EQ(cellTriangles[info.id].count(key), touches ? 1u : 0u) << info.name;
      cells += touches;
    }
    EXPECT_GE(cells, 1u);
    references += cells;
  }
  EXPECT_EQ(store.totalTriangles(), references);

  // The light is cut at the voxel faces it spans (x = -2.05, z = 0): four
  // pieces, each inside its voxel, with the power of the whole.
  ASSERT_EQ(store.lights().size(), 4u);
  Vec3 power(0);
  for (const AreaLight& light : store.lights()) {
    power += light.power();
    EXPECT_NEAR(light.normal().y, -1.0f, 1e-6f);
    const Bounds3& box = store.cells()[light.cell].bounds;
    const Bounds3 cell(box.lo - Vec3(1e-5f), box.hi + Vec3(1e-5f));
    for (const Vec3& corner : {light.corner, light.corner + light.edge1, light.corner + light.edge2,
                               light.corner + light.edge1 + light.edge2})
      EXPECT_TRUE(cell.contains(corner)) << "light " << light.id;
  }
  const float expectedPower = kPi * 0.36f * 20.0f;
  EXPECT_NEAR(power.x, expectedPower, 1e-3f * expectedPower);
  EXPECT_TRUE(store.cells()[store.camera().cell].bounds.contains(store.camera().origin));
}

TEST(BuildingImportGrid, CornellClosedInEightVoxels) {
  REQUIRE_REFERENCE_SCENE("cornell_closed");
  TempDirectory temp;
  ImportOptions options;
  options.gridResolution = 2;
  importBuilding({referenceJson("cornell_closed")}, temp / "store", options);
  const SceneStore store = SceneStore::open(temp / "store");
  EXPECT_EQ(store.cells().size(), 8u);
  EXPECT_EQ(store.portals().size(), 12u);
  // The light straddles x = 0: two pieces in the top layer.
  ASSERT_EQ(store.lights().size(), 2u);
  for (const AreaLight& light : store.lights()) EXPECT_GT(store.cells()[light.cell].bounds.lo.y, 0.5f);
  EXPECT_TRUE(store.cells()[store.camera().cell].bounds.contains(store.camera().origin));
  // Voxels cut through triangles: a voxel's triangles touch it, and may reach out of it.
  Bounds3 grid;
  for (const CellInfo& cell : store.cells()) grid.extend(cell.bounds);
  for (const CellInfo& info : store.cells()) {
    const auto cell = loadCell(store, info.id);
    for (uint32_t t = 0; t < cell->mesh().triangleCount; ++t) {
      Vec3 a, b, c;
      cell->mesh().triangle(t, a, b, c);
      EXPECT_TRUE(triangleOverlapsBox(a, b, c, info.bounds, 1e-5f * maxComponent(grid.diagonal())));
    }
  }
}

// ---------------------------------------------------------------- errors

// A broken building: a 2 m room made of one floor quad and a lamp, written
// to a temporary directory; each test breaks one thing.
struct BrokenBuilding {
  TempDirectory& temp;
  explicit BrokenBuilding(TempDirectory& t) : temp(t) {
    writeText(temp.path() / "floor.obj", "v 0 0 0\nv 0 0 2\nv 2 0 2\nv 2 0 0\nf 1 2 3\nf 1 3 4\n");
    writeText(temp.path() / "lamp.obj",
              "v 0.5 1.9 0.5\nv 1.5 1.9 0.5\nv 1.5 1.9 1.5\nv 0.5 1.9 1.5\nf 1 2 3\nf 1 3 4\n");
    writeText(temp.path() / "lamp3.obj",
              "v 0.5 1.9 0.5\nv 1.5 1.9 0.5\nv 1.5 1.9 1.5\nv 0.5 1.9 1.5\nv 1 1.9 2\nf 1 2 3\nf 1 3 4\nf 4 3 5\n");
  }
  // The building.json with `replacements` applied to its text.
  std::string json(const std::map<std::string, std::string>& replacements = {}) const {
    std::string text = R"({
  "units": "metres",
  "cells": [ {"name": "room", "aabb": {"min": [0, 0, 0], "max": [2, 2, 2]}},
             {"name": "hall", "aabb": {"min": [2, 0, 0], "max": [4, 2, 2]}} ],
  "portals": [ {"between": ["room", "hall"], "polygon": [[2, 0, 0.5], [2, 0, 1.5], [2, 1.5, 1.5], [2, 1.5, 0.5]]} ],
  "objects": [
    {"obj": "floor.obj", "name": "floor", "cell": "room", "albedo": [0.5, 0.5, 0.5], "emission": null},
    {"obj": "lamp.obj", "name": "lamp", "cell": "room", "albedo": [0, 0, 0], "emission": [10, 10, 10]}
  ],
  "camera": {"origin": [1, 1, 1.8], "target": [1, 1, 0], "up": [0, 1, 0], "fov_y_deg": 60, "width": 64, "height": 48}
})";
    for (const auto& [from, to] : replacements) {
      const size_t at = text.find(from);
      if (at == std::string::npos) ADD_FAILURE() << "'" << from << "' not in the json";
      else text.replace(at, from.size(), to);
    }
    const fs::path path = temp.path() / "building.json";
    writeText(path, text);
    return path.string();
  }
  // Imports and returns the error message; checks no store was left behind.
  std::string importError(const std::map<std::string, std::string>& replacements) const {
    const std::string path = json(replacements);
    const std::string store = temp / "store";
    const std::string error = errorOf([&] { importBuilding({path}, store); });
    EXPECT_FALSE(fs::exists(store)) << "a failed import left " << store;
    for (const auto& entry : fs::directory_iterator(temp.path()))
      EXPECT_EQ(entry.path().filename().string().find("store."), std::string::npos) << entry.path();
    EXPECT_EQ(error.find('\n'), std::string::npos) << "not one line: " << error;
    return error;
  }
  // Imports with the floor's mesh replaced by `file` holding `contents`;
  // returns the error, after checking it names the file and the object.
  std::string floorMeshError(const std::string& file, const std::string& contents) const {
    writeText(temp.path() / file, contents);
    const std::string error = importError({{"\"floor.obj\"", "\"" + file + "\""}});
    EXPECT_NE(error.find(file), std::string::npos) << error;
    EXPECT_NE(error.find("'floor'"), std::string::npos) << error;
    return error;
  }
};

TEST(BuildingImportErrors, TheUnbrokenBuildingImports) {
  TempDirectory temp;
  BrokenBuilding building(temp);
  importBuilding({building.json()}, temp / "store");
  const SceneStore store = SceneStore::open(temp / "store");
  EXPECT_EQ(store.cells().size(), 2u);
  EXPECT_EQ(store.cells()[1].triangleCount, 0u);
  EXPECT_EQ(store.lights().size(), 1u);
  EXPECT_EQ(store.camera().cell, 0u);
}

// "site": where the building stands, kept in the store (exactly, as
// doubles) and through a --grid re-cut; without it the store has none.
TEST(BuildingImport, KeepsTheSiteThroughAReCut) {
  TempDirectory temp;
  BrokenBuilding building(temp);
  importBuilding({building.json({{"\"units\": \"metres\",",
                                  "\"units\": \"metres\", \"site\": {\"latitude\": 49.1003, \"longitude\": "
                                  "8.4366, \"north_azimuth\": 0.0},"}})},
                 temp / "store");
  const SiteLocation expected{49.1003, 8.4366, 0.0};
  ASSERT_TRUE(SceneStore::open(temp / "store").site());
  EXPECT_EQ(*SceneStore::open(temp / "store").site(), expected);
  ImportOptions grid;
  grid.gridResolution = 2;
  importBuilding({temp / "store"}, temp / "grid", grid);
  ASSERT_TRUE(SceneStore::open(temp / "grid").site());
  EXPECT_EQ(*SceneStore::open(temp / "grid").site(), expected);
  importBuilding({building.json()}, temp / "nowhere");
  EXPECT_FALSE(SceneStore::open(temp / "nowhere").site());
}

TEST(BuildingImportErrors, ASiteOffTheEarthNamesTheKey) {
  TempDirectory temp;
  BrokenBuilding building(temp);
  const auto withSite = [&](const std::string& site) {
    return building.importError({{"\"units\": \"metres\",", "\"units\": \"metres\", \"site\": " + site + ","}});
  };
  std::string error = withSite(R"({"latitude": 91, "longitude": 8})");
  EXPECT_NE(error.find("site.latitude = 91 must be a number of degrees from -90 to 90"), std::string::npos) << error;
  error = withSite(R"({"latitude": 49, "longitude": -180.5})");
  EXPECT_NE(error.find("site.longitude = -180.5 must be"), std::string::npos) << error;
  error = withSite(R"({"latitude": NaN, "longitude": 8})");
  EXPECT_NE(error.find("site.latitude is NaN, not a finite number"), std::string::npos) << error;
  error = withSite(R"({"latitude": "49", "longitude": 8})");
  EXPECT_NE(error.find("site.latitude must be a number"), std::string::npos) << error;
  error = withSite(R"({"longitude": 8})");
  EXPECT_NE(error.find("site has no \"latitude\""), std::string::npos) << error;
  error = withSite(R"({"latitude": 49, "longitude": 8, "north": 3})");
  EXPECT_NE(error.find("site: unknown key \"north\""), std::string::npos) << error;
  error = withSite("[49, 8]");
  EXPECT_NE(error.find("\"site\" must be an object"), std::string::npos) << error;
}

TEST(BuildingImportErrors, MissingMeshNamesTheFileAndObject) {
  TempDirectory temp;
  const std::string error = BrokenBuilding(temp).importError({{"\"floor.obj\"", "\"ghost.obj\""}});
  EXPECT_NE(error.find("ghost.obj"), std::string::npos) << error;
  EXPECT_NE(error.find("'floor'"), std::string::npos) << error;
  EXPECT_NE(error.find("does not exist"), std::string::npos) << error;
}

TEST(BuildingImportErrors, UnreadableMeshNamesTheFile) {
  TempDirectory temp;
  BrokenBuilding building(temp);
  building.floorMeshError("junk.obj", "this is not a mesh\n");
  const std::string error = building.floorMeshError("junk.glb", "glTF but not really");
  EXPECT_NE(error.find("cannot be read"), std::string::npos) << error;
  fs::create_directory(temp.path() / "folder.obj");
  EXPECT_NE(building.importError({{"\"floor.obj\"", "\"folder.obj\""}}).find("is not a regular file"),
            std::string::npos);
}

TEST(BuildingImportErrors, NonFiniteMeshVertexNamesTheFileAndObject) {
  TempDirectory temp;
  const std::string error = BrokenBuilding(temp).floorMeshError("nan.obj", "v 0 0 0\nv nan 0 2\nv 2 0 2\nf 1 2 3\n");
  EXPECT_NE(error.find("vertex 1 is not finite"), std::string::npos) << error;
}

TEST(BuildingImportErrors, UnknownCellNamesTheObjectAndCell) {
  TempDirectory temp;
  const std::string error = BrokenBuilding(temp).importError(
      {{"\"cell\": \"room\", \"albedo\": [0.5", "\"cell\": \"attic\", \"albedo\": [0.5"}});
  EXPECT_NE(error.find("'attic'"), std::string::npos) << error;
  EXPECT_NE(error.find("'floor'"), std::string::npos) << error;
  EXPECT_NE(error.find("building.json"), std::string::npos) << error;
}

TEST(BuildingImportErrors, NanAlbedoNamesTheObject) {
  TempDirectory temp;
  const std::string error = BrokenBuilding(temp).importError({{"[0.5, 0.5, 0.5]", "[0.5, NaN, 0.5]"}});
  EXPECT_NE(error.find("'floor'"), std::string::npos) << error;
  EXPECT_NE(error.find("albedo[1]"), std::string::npos) << error;
  EXPECT_NE(error.find("NaN"), std::string::npos) << error;
}

TEST(BuildingImportErrors, OverflowingNumberIsNotFinite) {
  TempDirectory temp;
  const std::string error = BrokenBuilding(temp).importError({{"[1, 1, 1.8]", "[1, 1e39, 1.8]"}});
  EXPECT_NE(error.find("camera.origin[1]"), std::string::npos) << error;
}

TEST(BuildingImportErrors, AlbedoAboveOneNamesTheObject) {
  TempDirectory temp;
  const std::string error = BrokenBuilding(temp).importError({{"[0.5, 0.5, 0.5]", "[0.5, 1.5, 0.5]"}});
  EXPECT_NE(error.find("'floor'"), std::string::npos) << error;
  EXPECT_NE(error.find("[0, 1]"), std::string::npos) << error;
}

TEST(BuildingImport, AnEmitterOfAnyShapeIsTriangleLights) {
  TempDirectory temp;
  BrokenBuilding building(temp);
  importBuilding({building.json({{"\"lamp.obj\"", "\"lamp3.obj\""}})}, temp / "store");
  const SceneStore store = SceneStore::open(temp / "store");
  ASSERT_EQ(store.lights().size(), 3u);   // a square and a triangle: not one parallelogram
  float area = 0.0f;
  for (const AreaLight& light : store.lights()) {
    EXPECT_TRUE(light.isTriangle());
    EXPECT_EQ(light.radiance, Vec3(10.0f));
    EXPECT_NEAR(light.normal().y, -1.0f, 1e-6f);   // the OBJ's winding faces down
    area += light.area();
  }
  EXPECT_NEAR(area, 1.25f, 1e-5f);
}

TEST(BuildingImportErrors, CameraOutsideEveryCell) {
  TempDirectory temp;
  const std::string error = BrokenBuilding(temp).importError({{"[1, 1, 1.8]", "[1, 5, 1.8]"}});
  EXPECT_NE(error.find("camera"), std::string::npos) << error;
  EXPECT_NE(error.find("outside every cell"), std::string::npos) << error;
}

TEST(BuildingImportErrors, MissingCamera) {
  TempDirectory temp;
  const std::string error = BrokenBuilding(temp).importError({{"\"camera\":", "\"_view\":"}});
  EXPECT_NE(error.find("has no \"camera\""), std::string::npos) << error;
}

TEST(BuildingImportErrors, TriangleOutsideItsCellNamesObjectAndCell) {
  TempDirectory temp;
  BrokenBuilding building(temp);
  writeText(temp.path() / "floor.obj", "v 0 0 0\nv 0 0 2\nv 2.5 0 2\nf 1 2 3\n");
  const std::string error = building.importError({});
  EXPECT_NE(error.find("'floor'"), std::string::npos) << error;
  EXPECT_NE(error.find("cell 'room'"), std::string::npos) << error;
}

TEST(BuildingImportErrors, BrokenPortals) {
  TempDirectory temp;
  BrokenBuilding building(temp);
  std::string error = building.importError({{"[\"room\", \"hall\"]", "[\"room\", \"cellar\"]"}});
  EXPECT_NE(error.find("portals[0]"), std::string::npos) << error;
  EXPECT_NE(error.find("'cellar'"), std::string::npos) << error;
  error = building.importError(
      {{"[[2, 0, 0.5], [2, 0, 1.5], [2, 1.5, 1.5], [2, 1.5, 0.5]]", "[[2, 0, 0.5], [2, 0, 1.5]]"}});
  EXPECT_NE(error.find("portals[0] (room - hall)"), std::string::npos) << error;
  EXPECT_NE(error.find("at least 3"), std::string::npos) << error;
  error = building.importError({{"[2, 1.5, 0.5]]", "[1.8, 1.5, 0.5]]"}});
  EXPECT_NE(error.find("not planar"), std::string::npos) << error;
}

TEST(BuildingImportErrors, MalformedJsonNamesTheFile) {
  TempDirectory temp;
  const std::string error = BrokenBuilding(temp).importError({{"\"units\": \"metres\",", "\"units\": \"metres\""}});
  EXPECT_NE(error.find("building.json: not valid JSON"), std::string::npos) << error;
  EXPECT_NE(error.find("line 3"), std::string::npos) << error;
}

TEST(BuildingImportErrors, UnknownKeysAreNamed) {
  TempDirectory temp;
  BrokenBuilding building(temp);
  // A misspelt "emission" would otherwise turn the lamp off without a word.
  std::string error = building.importError({{"\"emission\": [10, 10, 10]", "\"emision\": [10, 10, 10]"}});
  EXPECT_NE(error.find("building.json: objects[1] ('lamp'): unknown key \"emision\""), std::string::npos) << error;
  EXPECT_NE(error.find("known: obj, mesh, name, cell, albedo, emission"), std::string::npos) << error;
  error = building.importError({{"\"portals\":", "\"portal\":"}});
  EXPECT_NE(error.find("top level: unknown key \"portal\""), std::string::npos) << error;
  error = building.importError({{"\"max\": [2, 2, 2]", "\"max\": [2, 2, 2], \"maxx\": 1"}});
  EXPECT_NE(error.find("cell 'room' aabb: unknown key \"maxx\""), std::string::npos) << error;
  error = building.importError({{"\"fov_y_deg\": 60", "\"fov\": 60"}});
  EXPECT_NE(error.find("camera: unknown key \"fov\""), std::string::npos) << error;
  error = building.importError({{"\"between\":", "\"betwen\": [], \"between\":"}});
  EXPECT_NE(error.find("portals[0]: unknown key \"betwen\""), std::string::npos) << error;
}

TEST(BuildingImport, DescriptiveAndUnderscoreKeysAreIgnored) {
  TempDirectory temp;
  BrokenBuilding building(temp);
  const std::string path =
      building.json({{"\"units\": \"metres\",", "\"units\": \"metres\", \"description\": \"x\", \"_by\": \"me\","},
                     {"\"name\": \"floor\",", "\"name\": \"floor\", \"triangles\": 2, \"_source\": 1,"}});
  importBuilding({path}, temp / "store");
  EXPECT_EQ(SceneStore::open(temp / "store").totalTriangles(), 4u);
}

TEST(BuildingImportErrors, InfiniteMeshVertexNamesTheFileAndObject) {
  TempDirectory temp;
  BrokenBuilding building(temp);
  std::string error = building.floorMeshError("inf.obj", "v 0 0 0\nv 0 0 2\nv 2 0 inf\nf 1 2 3\n");
  EXPECT_NE(error.find("vertex 2 is not finite"), std::string::npos) << error;
  error = building.floorMeshError("huge.obj", "v 0 0 0\nv 0 1e39 2\nv 2 0 2\nf 1 2 3\n");   // beyond float
  EXPECT_NE(error.find("vertex 1 is not finite"), std::string::npos) << error;
}

TEST(BuildingImport, DegenerateTrianglesAreDroppedAndCounted) {
  TempDirectory temp;
  BrokenBuilding building(temp);
  // Two good triangles, one with a repeated corner, one with three corners on a line.
  writeText(temp.path() / "floor.obj",
            "v 0 0 0\nv 0 0 2\nv 2 0 2\nv 2 0 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\nf 1 2 2\nf 1 5 2\n");
  const ImportSummary summary = importBuilding({building.json()}, temp / "store");
  EXPECT_EQ(summary.degenerateTrianglesDropped, 2u);
  EXPECT_EQ(summary.triangles, 4u);   // the floor's 2 and the lamp's 2
  const SceneStore store = SceneStore::open(temp / "store");
  EXPECT_EQ(store.totalTriangles(), 4u);
  EXPECT_EQ(store.meta().at("degenerate_triangles_dropped"), "2");
}

TEST(BuildingImportErrors, AMeshOfOnlyDegenerateTrianglesIsEmpty) {
  TempDirectory temp;
  const std::string error = BrokenBuilding(temp).floorMeshError("flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
  EXPECT_NE(error.find("has no triangles but 1 degenerate"), std::string::npos) << error;
}

TEST(BuildingImportErrors, EmptyScenes) {
  TempDirectory temp;
  BrokenBuilding building(temp);
  std::string error = building.importError(
      {{"{\"obj\": \"floor.obj\", \"name\": \"floor\", \"cell\": \"room\", \"albedo\": [0.5, 0.5, 0.5], \"emission\": "
        "null},",
        ""},
       {"{\"obj\": \"lamp.obj\", \"name\": \"lamp\", \"cell\": \"room\", \"albedo\": [0, 0, 0], \"emission\": [10, "
        "10, 10]}",
        ""}});
  EXPECT_NE(error.find("building.json: \"objects\" must be a non-empty array"), std::string::npos) << error;
  // A mesh file without a triangle, in a building.json and on its own.
  building.floorMeshError("points.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\n");
  error = errorOf([&] { importBuilding({temp / "points.obj"}, temp / "store"); });
  EXPECT_NE(error.find("points.obj"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(temp / "store"));
}

TEST(BuildingImportErrors, PortalsOffTheirCellsBoundaries) {
  TempDirectory temp;
  BrokenBuilding building(temp);
  const std::string onTheWall = "[[2, 0, 0.5], [2, 0, 1.5], [2, 1.5, 1.5], [2, 1.5, 0.5]]";
  const std::string inTheRoom = "[[1, 0, 0.5], [1, 0, 1.5], [1, 1.5, 1.5], [1, 1.5, 0.5]]";
  // In the room, short of the wall it shares with the hall.
  std::string error = building.importError({{onTheWall, inTheRoom}});
  EXPECT_NE(error.find("portals[0] (room - hall): polygon is not on the boundary of cell 'room'"), std::string::npos)
      << error;
  // Overlapping cells: on the hall's face but inside the room, so a ray
  // crossing it would not leave the room.
  error = building.importError({{"\"min\": [2, 0, 0]", "\"min\": [1, 0, 0]"}, {onTheWall, inTheRoom}});
  EXPECT_NE(error.find("not on the boundary of cell 'room': lies inside the box"), std::string::npos) << error;
  EXPECT_EQ(error.find("cell 'hall'"), std::string::npos) << error;
}

TEST(BuildingImportErrors, AFailedImportLeavesTheOldStoreAsItWas) {
  TempDirectory temp;
  BrokenBuilding building(temp);
  importBuilding({building.json()}, temp / "store");
  const std::vector<char> before = testing_support::readBytes(temp.path() / "store" / "scene.db");
  const std::string path = building.json({{"\"floor.obj\"", "\"ghost.obj\""}});
  EXPECT_NE(errorOf([&] { importBuilding({path}, temp / "store"); }).find("ghost.obj"), std::string::npos);
  EXPECT_EQ(testing_support::readBytes(temp.path() / "store" / "scene.db"), before);
  EXPECT_EQ(SceneStore::open(temp / "store").totalTriangles(), 4u);
  EXPECT_FALSE(testing_support::hasEntryStartingWith(temp.path(), "store."));
}

TEST(BuildingImportErrors, BuildingJsonMustBeTheOnlyInput) {
  TempDirectory temp;
  BrokenBuilding building(temp);
  const std::string error = errorOf([&] { importBuilding({building.json(), temp / "floor.obj"}, temp / "store"); });
  EXPECT_NE(error.find("only input"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(temp / "store"));
}

TEST(BuildingImport, CamerasAreChosenByName) {
  TempDirectory temp;
  BrokenBuilding building(temp);
  const std::string path = building.json(
      {{"\"camera\": {\"origin\": [1, 1, 1.8]",
        "\"cameras\": [{\"name\": \"hall\", \"origin\": [3, 1, 1], \"target\": [0, 1, 1]}, "
        "{\"name\": \"room\", \"origin\": [1, 1, 1.8]"},
       {"\"height\": 48}", "\"height\": 48}]"}});
  importBuilding({path}, temp / "first");
  EXPECT_EQ(SceneStore::open(temp / "first").camera().cell, 1u);   // the hall
  EXPECT_EQ(SceneStore::open(temp / "first").camera().width, 512u);   // the default
  ImportOptions options;
  options.camera = "room";
  importBuilding({path}, temp / "second", options);
  EXPECT_EQ(SceneStore::open(temp / "second").camera().cell, 0u);
  EXPECT_EQ(SceneStore::open(temp / "second").camera().width, 64u);
  // Every camera is stored by name, the chosen one first (the default).
  for (const char* store : {"first", "second"}) {
    const SceneStore stored = SceneStore::open(temp / store);
    ASSERT_EQ(stored.cameras().size(), 2u) << store;
    EXPECT_EQ(stored.camera().name, std::string(store) == "first" ? "hall" : "room");
    ASSERT_NE(stored.findCamera("hall"), nullptr);
    ASSERT_NE(stored.findCamera("room"), nullptr);
    EXPECT_EQ(stored.findCamera("hall")->cell, 1u);
    EXPECT_EQ(stored.findCamera("room")->cell, 0u);
    EXPECT_EQ(stored.findCamera("room")->width, 64u);
  }
  // Re-cut into voxels, the cameras stay, each in the voxel of its eye.
  ImportOptions grid;
  grid.gridResolution = 2;
  importBuilding({temp / "second"}, temp / "voxels", grid);
  const SceneStore voxels = SceneStore::open(temp / "voxels");
  ASSERT_EQ(voxels.cameras().size(), 2u);
  EXPECT_EQ(voxels.camera().name, "room");
  EXPECT_EQ(voxels.cameras()[1].name, "hall");
  for (const Camera& camera : voxels.cameras())
    EXPECT_TRUE(voxels.cells()[camera.cell].bounds.contains(camera.origin)) << camera.name;
  options.camera = "attic";
  const std::string error = errorOf([&] { importBuilding({path}, temp / "third", options); });
  EXPECT_NE(error.find("no camera named 'attic'"), std::string::npos) << error;
}

// ---------------------------------------------------------------- mesh files

TEST(BuildingImportMeshes, ObjWithMaterialsBecomesOneCell) {
  TempDirectory temp;
  writeText(temp.path() / "room.mtl",
            "newmtl white\nKd 0.5 0.6 1.7\n\nnewmtl lamp\nKd 0 0 0\nKe 5 4 3\n");
  writeText(temp.path() / "room.obj",
            "mtllib room.mtl\n"
            "v 0 0 0\nv 0 0 3\nv 4 0 3\nv 4 0 0\n"               // floor, facing +y
            "v 1 2 1\nv 3 2 1\nv 3 2 2\nv 1 2 2\n"               // lamp, facing -y
            "o floor\nusemtl white\nf 1 2 3 4\n"
            "o lamp\nusemtl lamp\nf 5 6 7\nf 5 7 8\n");
  importBuilding({temp / "room.obj"}, temp / "store");
  const SceneStore store = SceneStore::open(temp / "store");
  ASSERT_EQ(store.cells().size(), 1u);
  EXPECT_EQ(store.totalTriangles(), 4u);
  const Bounds3& bounds = store.cells()[0].bounds;
  EXPECT_NEAR(bounds.lo.x, -0.001f, 1e-6f);
  EXPECT_NEAR(bounds.hi.y, 2.001f, 1e-6f);
  EXPECT_NEAR(bounds.hi.z, 3.001f, 1e-6f);

  bool white = false;
  for (const Material& material : store.materials())
    if (material.name == "white") {
      white = true;
      EXPECT_EQ(material.albedo, Vec3(0.5f, 0.6f, 1.0f));   // clamped to [0, 1]
    }
  EXPECT_TRUE(white);
  ASSERT_EQ(store.lights().size(), 1u);
  EXPECT_EQ(store.lights()[0].radiance, Vec3(5, 4, 3));
  EXPECT_NEAR(store.lights()[0].normal().y, -1.0f, 1e-6f);
  EXPECT_NEAR(store.lights()[0].area(), 2.0f, 1e-6f);

  const Camera& camera = store.camera();
  EXPECT_EQ(camera.origin, Vec3(2.0f, 1.0f, 1.5f));
  EXPECT_EQ(camera.target, Vec3(2.0f, 1.0f, 0.5f));
  EXPECT_EQ(camera.fovYDegrees, 60.0f);
  EXPECT_EQ(camera.width, 512u);
  EXPECT_EQ(camera.height, 384u);
  EXPECT_EQ(camera.cell, 0u);
  // The polygon was triangulated with its winding: the floor still faces up.
  EXPECT_NEAR(normalOfTriangleAt(store, 0, [](const Vec3& p) { return p.y == 0.0f; }).y, 1.0f, 1e-6f);
}

TEST(BuildingImportMeshes, SeveralFilesAndAGrid) {
  TempDirectory temp;
  writeText(temp.path() / "a.obj", "v 0 0 0\nv 0 0 1\nv 1 0 1\nf 1 2 3\n");
  writeText(temp.path() / "b.ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
            "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
            "3 1 0\n3 1 1\n4 1 1\n3 0 1 2\n");
  ImportOptions options;
  options.gridResolution = 3;
  importBuilding({temp / "a.obj", temp / "b.ply"}, temp / "store", options);
  const SceneStore store = SceneStore::open(temp / "store");
  EXPECT_EQ(store.cells().size(), 27u);
  EXPECT_EQ(store.portals().size(), 54u);
  EXPECT_GE(store.totalTriangles(), 2u);
  EXPECT_TRUE(store.lights().empty());
  EXPECT_TRUE(store.cells()[store.camera().cell].bounds.contains(store.camera().origin));
}

// A glTF file holding the triangle (0,0,0) (1,0,0) (0,0,-1), facing +y, of
// base colour (0.25, 0.5, 0.75), under one node with `nodeTransform` (json members).
std::string gltfTriangle(const std::string& nodeTransform) {
  std::vector<uint8_t> bytes;
  auto putFloat = [&](float f) {
    uint8_t b[4];
    std::memcpy(b, &f, 4);
    bytes.insert(bytes.end(), b, b + 4);
  };
  for (float f : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 0.f, -1.f}) putFloat(f);
  for (uint16_t i : {0, 1, 2, 0}) bytes.insert(bytes.end(), {uint8_t(i & 0xff), uint8_t(i >> 8)});
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string base64;
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const uint32_t n = (uint32_t(bytes[i]) << 16) | (i + 1 < bytes.size() ? uint32_t(bytes[i + 1]) << 8 : 0) |
                       (i + 2 < bytes.size() ? uint32_t(bytes[i + 2]) : 0);
    base64 += kAlphabet[(n >> 18) & 63];
    base64 += kAlphabet[(n >> 12) & 63];
    base64 += i + 1 < bytes.size() ? kAlphabet[(n >> 6) & 63] : '=';
    base64 += i + 2 < bytes.size() ? kAlphabet[n & 63] : '=';
  }
  return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
  "nodes": [{"mesh": 0, )" + nodeTransform + R"(}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
  "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.25, 0.5, 0.75, 1]}}],
  "buffers": [{"byteLength": 44, "uri": "data:application/octet-stream;base64,)" + base64 + R"("}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [0, 0, -1], "max": [1, 0, 0]},
                {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]})";
}

TEST(BuildingImportMeshes, GltfNodeTransformsAreApplied) {
  TempDirectory temp;
  writeText(temp.path() / "tri.gltf", gltfTriangle(R"("translation": [10, 0, 0])"));
  importBuilding({temp / "tri.gltf"}, temp / "store");
  const SceneStore store = SceneStore::open(temp / "store");
  EXPECT_NEAR(store.cells()[0].bounds.lo.x, 9.999f, 1e-5f);
  EXPECT_NEAR(store.cells()[0].bounds.hi.x, 11.001f, 1e-5f);
  ASSERT_EQ(store.materials().size(), 1u);
  EXPECT_EQ(store.materials()[0].albedo, Vec3(0.25f, 0.5f, 0.75f));
  EXPECT_NEAR(normalOfTriangleAt(store, 0, [](const Vec3&) { return true; }).y, 1.0f, 1e-6f);
}

TEST(BuildingImportMeshes, GltfMirroringNodeKeepsTheFront) {
  TempDirectory temp;
  writeText(temp.path() / "tri.gltf", gltfTriangle(R"("scale": [-1, 1, 1])"));
  importBuilding({temp / "tri.gltf"}, temp / "store");
  const SceneStore store = SceneStore::open(temp / "store");
  EXPECT_NEAR(store.cells()[0].bounds.lo.x, -1.001f, 1e-5f);
  EXPECT_NEAR(normalOfTriangleAt(store, 0, [](const Vec3&) { return true; }).y, 1.0f, 1e-6f);
}

// emissiveFactor stops at 1; KHR_materials_emissive_strength scales it
// (read from the file's JSON: Debian's Assimp drops the extension).
TEST(BuildingImportMeshes, GltfEmissiveStrengthScalesTheEmission) {
  TempDirectory temp;
  std::string text = gltfTriangle(R"("translation": [0, 0, 0])");
  const std::string plain = R"("materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.25, 0.5, 0.75, 1]}}])";
  ASSERT_NE(text.find(plain), std::string::npos);
  text.replace(text.find(plain), plain.size(),
               R"("materials": [{"emissiveFactor": [1, 0.5, 0.25],
                   "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 40}}}],
                  "extensionsUsed": ["KHR_materials_emissive_strength"])");
  writeText(temp.path() / "lamp.gltf", text);
  importBuilding({temp / "lamp.gltf"}, temp / "store");
  const SceneStore store = SceneStore::open(temp / "store");
  ASSERT_EQ(store.lights().size(), 1u);
  EXPECT_EQ(store.lights()[0].radiance, Vec3(40.0f, 20.0f, 10.0f));
}

TEST(BuildingImportMeshes, AnEmissiveTriangleIsATriangleLight) {
  TempDirectory temp;
  writeText(temp.path() / "glow.mtl", "newmtl glow\nKd 0 0 0\nKe 1 2 3\n");
  writeText(temp.path() / "glow.obj", "mtllib glow.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl glow\nf 1 2 3\n");
  const ImportSummary summary = importBuilding({temp / "glow.obj"}, temp / "store");
  EXPECT_EQ(summary.lights, 1u);
  EXPECT_TRUE(summary.warnings.empty());
  const SceneStore store = SceneStore::open(temp / "store");
  ASSERT_EQ(store.lights().size(), 1u);
  const AreaLight& light = store.lights()[0];
  EXPECT_TRUE(light.isTriangle());
  EXPECT_EQ(light.radiance, Vec3(1, 2, 3));
  EXPECT_NEAR(light.area(), 0.5f, 1e-6f);
  EXPECT_NEAR(light.normal().z, 1.0f, 1e-6f);
  EXPECT_NEAR(light.power().x, kPi * 0.5f, 1e-5f);
}

// ---------------------------------------------------------------- materials and lights of the files

// A room's floor (red) and back wall (green) in one OBJ + MTL.
void writeTwoColourRoom(const fs::path& dir) {
  writeText(dir / "room.mtl", "newmtl red\nKd 0.7 0.1 0.1\nnewmtl green\nKd 0.1 0.6 0.2\n");
  writeText(dir / "room.obj",
            "mtllib room.mtl\nv 0 0 0\nv 0 0 2\nv 2 0 2\nv 2 0 0\nv 0 2 0\nv 2 2 0\n"
            "usemtl red\nf 1 2 3 4\nusemtl green\nf 1 4 6 5\n");
}

std::string twoColourBuilding(const std::string& lights) {
  return R"({"objects": [{"obj": "room.obj", "name": "room"}],
  "lights": )" + lights + R"(,
  "camera": {"origin": [1, 1, 1.5], "target": [1, 1, 0]}})";
}

TEST(BuildingImport, AnObjectWithoutAlbedoTakesTheFilesMaterials) {
  TempDirectory temp;
  writeTwoColourRoom(temp.path());
  writeText(temp.path() / "building.json", twoColourBuilding("[]"));
  importBuilding({temp / "building.json"}, temp / "store");
  const SceneStore store = SceneStore::open(temp / "store");
  ASSERT_EQ(store.cells().size(), 1u);
  const auto cell = loadCell(store, 0);
  const MeshView& mesh = cell->mesh();
  ASSERT_EQ(mesh.triangleCount, 4u);
  for (uint32_t t = 0; t < mesh.triangleCount; ++t) {
    Vec3 a, b, c;
    mesh.triangle(t, a, b, c);
    const bool floor = a.y == 0.0f && b.y == 0.0f && c.y == 0.0f;
    const Material& material = store.materials()[cell->material(t)];
    EXPECT_EQ(material.albedo, floor ? Vec3(0.7f, 0.1f, 0.1f) : Vec3(0.1f, 0.6f, 0.2f)) << "triangle " << t;
    EXPECT_EQ(material.name, floor ? "red" : "green");
    EXPECT_FALSE(material.emissive());
  }
}

TEST(BuildingImport, TheLightsArrayAddsQuadsAndTriangles) {
  TempDirectory temp;
  writeTwoColourRoom(temp.path());
  writeText(temp.path() / "building.json",
            twoColourBuilding(R"([{"name": "panel", "quad": {"corner": [0.5, 1.9, 0.5], "edge1": [1, 0, 0],
                                   "edge2": [0, 0, 0.5]}, "radiance": [8, 8, 8]},
                                  {"triangle": [[0.2, 0.5, 1.8], [0.6, 0.5, 1.8], [0.2, 0.9, 1.8]],
                                   "radiance": [1, 2, 3]}])"));
  const ImportSummary summary = importBuilding({temp / "building.json"}, temp / "store");
  EXPECT_EQ(summary.lights, 2u);
  EXPECT_TRUE(summary.warnings.empty());
  const SceneStore store = SceneStore::open(temp / "store");
  ASSERT_EQ(store.lights().size(), 2u);
  const AreaLight& panel = store.lights()[0];
  EXPECT_FALSE(panel.isTriangle());
  EXPECT_NEAR(panel.area(), 0.5f, 1e-6f);
  EXPECT_NEAR(panel.normal().y, -1.0f, 1e-6f);   // cross(edge1, edge2): down
  const AreaLight& triangle = store.lights()[1];
  EXPECT_TRUE(triangle.isTriangle());
  EXPECT_NEAR(triangle.area(), 0.08f, 1e-6f);
  EXPECT_NEAR(triangle.normal().z, 1.0f, 1e-6f);
  EXPECT_EQ(triangle.radiance, Vec3(1, 2, 3));
  // Both are geometry too: 4 room + 2 panel + 1 triangle, emissive on the side they face.
  const auto cell = loadCell(store, 0);
  ASSERT_EQ(cell->mesh().triangleCount, 7u);
  int emissive = 0;
  for (uint32_t t = 0; t < cell->mesh().triangleCount; ++t) {
    const Material& material = store.materials()[cell->material(t)];
    if (!material.emissive()) continue;
    ++emissive;
    const Vec3 n = normalize(cell->mesh().geometricNormal(t));
    EXPECT_GT(dot(n, material.emission.x == 8.0f ? panel.normal() : triangle.normal()), 0.999f);
  }
  EXPECT_EQ(emissive, 3);
}

TEST(BuildingImport, AStoreKeepsTriangleLightsAcrossARecut) {
  TempDirectory temp;
  writeTwoColourRoom(temp.path());
  writeText(temp.path() / "building.json",
            twoColourBuilding(R"([{"triangle": [[0.2, 0.5, 1.8], [0.6, 0.5, 1.8], [0.2, 0.9, 1.8]],
                                   "radiance": [1, 1, 1]}])"));
  importBuilding({temp / "building.json"}, temp / "store");
  ImportOptions grid;
  grid.gridResolution = 2;
  importBuilding({temp / "store"}, temp / "voxels", grid);
  const SceneStore store = SceneStore::open(temp / "voxels");
  ASSERT_EQ(store.lights().size(), 1u);
  EXPECT_TRUE(store.lights()[0].isTriangle());
  EXPECT_NEAR(store.lights()[0].area(), 0.08f, 1e-6f);
  EXPECT_TRUE(store.cells()[store.lights()[0].cell].bounds.contains(store.lights()[0].center()));
}

TEST(BuildingImportErrors, BrokenLightsAreNamed) {
  TempDirectory temp;
  writeTwoColourRoom(temp.path());
  const std::map<std::string, std::string> cases{
      {R"([{"radiance": [1, 1, 1]}])", "lights[0] ('light-0') needs one shape"},
      {R"([{"quad": {"corner": [0, 1, 0], "edge1": [1, 0, 0], "edge2": [0, 0, 1]},
            "triangle": [[0, 1, 0], [1, 1, 0], [0, 1, 1]], "radiance": [1, 1, 1]}])", "needs one shape"},
      {R"([{"name": "flat", "triangle": [[0, 1, 0], [1, 1, 0], [2, 1, 0]], "radiance": [1, 1, 1]}])",
       "lights[0] ('flat'): the triangle has zero area"},
      {R"([{"triangle": [[0, 1, 0], [1, 1, 0]], "radiance": [1, 1, 1]}])", "must be an array of 3 points"},
      {R"([{"quad": {"corner": [0, 1, 0], "edge1": [1, 0, 0]}, "radiance": [1, 1, 1]}])", "quad has no \"edge2\""},
      {R"([{"triangle": [[0, 1, 0], [1, 1, 0], [0, 1, 1]], "radiance": [1, -1, 1]}])", "must not be negative"},
      {R"([{"triangle": [[0, 1, 0], [1, 1, 0], [0, 1, 1]], "radiance": [0, 0, 0]}])", "radiance is zero"},
      {R"([{"triangle": [[0, 1, 0], [1, 1, 0], [0, 1, 1]]}])", "has no \"radiance\""},
      {R"([{"triangle": [[0, 1, 0], [1, 1, 0], [0, 1, 1]], "radiance": [1, 1, 1], "cell": "attic"}])",
       "unknown cell 'attic'"},
      {R"([{"triangle": [[0, 1, 0], [1, 1, 0], [0, 1, 1]], "radiance": [1, 1, 1], "power": 60}])",
       "unknown key \"power\""},
      {R"({"quad": {}})", "\"lights\" must be an array"}};
  for (const auto& [lights, expected] : cases) {
    writeText(temp.path() / "building.json", twoColourBuilding(lights));
    const std::string error = errorOf([&] { importBuilding({temp / "building.json"}, temp / "store"); });
    EXPECT_NE(error.find(expected), std::string::npos) << lights << " -> " << error;
    EXPECT_EQ(error.find('\n'), std::string::npos) << error;
    EXPECT_FALSE(fs::exists(temp / "store"));
  }
}

TEST(BuildingImport, ASceneWithoutLightsWarnsHowToAddOne) {
  TempDirectory temp;
  writeTwoColourRoom(temp.path());
  const ImportSummary summary = importBuilding({temp / "room.obj"}, temp / "store");
  EXPECT_EQ(summary.lights, 0u);
  ASSERT_EQ(summary.warnings.size(), 1u);
  const std::string& warning = summary.warnings[0];
  EXPECT_NE(warning.find("no lights"), std::string::npos) << warning;
  EXPECT_NE(warning.find("\"lights\" array"), std::string::npos) << warning;
  EXPECT_NE(warning.find("emissive material"), std::string::npos) << warning;
  EXPECT_NE(warning.find("--lights panels"), std::string::npos) << warning;
  EXPECT_EQ(warning.find('\n'), std::string::npos) << warning;
}

// ---------------------------------------------------------------- helpers

TEST(BuildingImportOverlap, SeparatingAxes) {
  const Bounds3 box(Vec3(0), Vec3(1));
  // Inside, crossing, touching a face, and far away.
  EXPECT_TRUE(triangleOverlapsBox(Vec3(0.2f, 0.2f, 0.5f), Vec3(0.8f, 0.2f, 0.5f), Vec3(0.5f, 0.8f, 0.5f), box, 0));
  EXPECT_TRUE(triangleOverlapsBox(Vec3(-5, 0.5f, -5), Vec3(5, 0.5f, -5), Vec3(0, 0.5f, 5), box, 0));
  EXPECT_TRUE(triangleOverlapsBox(Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(1, 0, 1), box, 0));
  EXPECT_FALSE(triangleOverlapsBox(Vec3(2, 2, 2), Vec3(3, 2, 2), Vec3(2, 3, 2), box, 0));
  // Its bounding box covers the box's corner, but the triangle passes it by
  // (only an edge cross product separates them).
  EXPECT_FALSE(triangleOverlapsBox(Vec3(0.9f, 2, 0.5f), Vec3(2, 0.9f, 0.5f), Vec3(2, 2, 0.5f), box, 0));
  // The same, but only the triangle's plane separates them.
  EXPECT_FALSE(triangleOverlapsBox(Vec3(1.5f, 1.5f, 0.5f), Vec3(0.5f, 1.5f, 1.5f), Vec3(1.5f, 0.5f, 1.5f), box, 0));
  // The tolerance grows the box.
  EXPECT_FALSE(triangleOverlapsBox(Vec3(1.01f, 0, 0), Vec3(1.01f, 1, 0), Vec3(1.01f, 0, 1), box, 0.005f));
  EXPECT_TRUE(triangleOverlapsBox(Vec3(1.01f, 0, 0), Vec3(1.01f, 1, 0), Vec3(1.01f, 0, 1), box, 0.02f));
}

TEST(BuildingImportQuad, ParallelogramFromTwoTriangles) {
  std::string problem;
  // Unshared corners (as in the reference OBJs), then shared ones.
  const std::vector<float> separate{0, 0, 0, 2, 0, 0, 2, 0, 1, 0, 0, 0, 2, 0, 1, 0, 0, 1};
  auto quad = parallelogramFromTriangles(separate, {0, 2, 1, 3, 4, 5}, problem);
  EXPECT_FALSE(quad) << "opposite-facing triangles are not one quad";
  quad = parallelogramFromTriangles(separate, {0, 1, 2, 3, 4, 5}, problem);
  ASSERT_TRUE(quad) << problem;
  EXPECT_NEAR(length(cross(quad->edge1, quad->edge2)), 2.0f, 1e-6f);
  EXPECT_LT(cross(quad->edge1, quad->edge2).y, 0.0f);   // the triangles' own winding faces -y
  const std::vector<float> shared{0, 0, 0, 2, 0, 0, 3, 0, 1, 1, 0, 1};   // a slanted parallelogram
  quad = parallelogramFromTriangles(shared, {0, 2, 1, 0, 3, 2}, problem);
  ASSERT_TRUE(quad) << problem;
  EXPECT_GT(cross(quad->edge1, quad->edge2).y, 0.0f);
  const std::vector<float> kite{0, 0, 0, 2, 0, 0, 3, 0, 1, 0.5f, 0, 1};
  EXPECT_FALSE(parallelogramFromTriangles(kite, {0, 2, 1, 0, 3, 2}, problem));
  EXPECT_EQ(problem, "2 triangles that do not form a parallelogram");
}

}  // namespace
}  // namespace portico

// ---------------------------------------------------------------- glass

namespace portico {
namespace {

const Material* materialNamed(const SceneStore& store, const std::string& name) {
  for (const Material& material : store.materials())
    if (material.name == name) return &material;
  return nullptr;
}

TEST(BuildingImportGlass, MtlDissolveIsGlassTintedByTf) {
  TempDirectory temp;
  writeText(temp.path() / "w.mtl",
            "newmtl pane\nKd 0.2 0.2 0.2\nd 0.25\nTf 0.8 0.9 1.0\n\nnewmtl wall\nKd 0.5 0.5 0.5\n");
  writeText(temp.path() / "w.obj",
            "mtllib w.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nusemtl pane\nf 1 2 3\nusemtl wall\nf 1 3 4\n");
  importBuilding({temp / "w.obj"}, temp / "store");
  const SceneStore store = SceneStore::open(temp / "store");
  const Material* pane = materialNamed(store, "pane");
  const Material* wall = materialNamed(store, "wall");
  ASSERT_TRUE(pane && wall);
  ASSERT_TRUE(pane->glass());
  EXPECT_NEAR(pane->transmittance.x, 0.75f * 0.8f, 1e-6f);
  EXPECT_NEAR(pane->transmittance.z, 0.75f, 1e-6f);
  EXPECT_EQ(pane->albedo, Vec3(0));   // glass has no diffuse part
  EXPECT_FALSE(wall->glass());
}

// KHR_materials_transmission: transmitted light is tinted by the base colour.
TEST(BuildingImportGlass, GltfTransmissionIsGlassTintedByTheBaseColour) {
  TempDirectory temp;
  std::string text = gltfTriangle(R"("translation": [0, 0, 0])");
  const std::string plain = R"("materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.25, 0.5, 0.75, 1]}}])";
  ASSERT_NE(text.find(plain), std::string::npos);
  text.replace(text.find(plain), plain.size(),
               R"("materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.9, 1, 1]},
                   "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.5}}}],
                  "extensionsUsed": ["KHR_materials_transmission"])");
  writeText(temp.path() / "pane.gltf", text);
  importBuilding({temp / "pane.gltf"}, temp / "store");
  const SceneStore store = SceneStore::open(temp / "store");
  ASSERT_EQ(store.materials().size(), 1u);
  EXPECT_TRUE(store.materials()[0].glass());
  EXPECT_NEAR(store.materials()[0].transmittance.x, 0.4f, 1e-6f);
  EXPECT_NEAR(store.materials()[0].transmittance.z, 0.5f, 1e-6f);
}

TEST(BuildingImportGlass, BuildingJsonGlassKeyMakesThePaneOfTheDaylightScene) {
  TempDirectory temp;
  importBuilding({referenceJson("daylight_window")}, temp / "store");
  const SceneStore store = SceneStore::open(temp / "store");
  const Material* pane = materialNamed(store, "pane");
  ASSERT_NE(pane, nullptr);
  EXPECT_EQ(pane->transmittance, Vec3(0.75f, 0.85f, 0.95f));
  EXPECT_EQ(pane->ior, 1.5f);
  size_t glass = 0;
  for (const Material& material : store.materials()) glass += material.glass();
  EXPECT_EQ(glass, 1u);
}

TEST(BuildingImportGlass, GlassWithAnAlbedoOrAboveOneIsRefusedNamingTheObject) {
  TempDirectory temp;
  writeText(temp.path() / "t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const auto errorFor = [&](const std::string& object) {
    writeText(temp.path() / "b.json", R"({"objects": [)" + object + R"(], "camera": {"origin": [0.2, 0.2, 1],
              "target": [0.2, 0.2, 0], "up": [0, 1, 0], "fov_y_deg": 60, "width": 8, "height": 8}})");
    return errorOf([&] { importBuilding({temp / "b.json"}, temp / "store"); });
  };
  std::string error = errorFor(R"({"obj": "t.obj", "name": "pane", "albedo": [0.5, 0.5, 0.5],
                                   "glass": {"transmittance": [0.9, 0.9, 0.9]}})");
  EXPECT_NE(error.find("('pane'): \"glass\" is a material of its own"), std::string::npos) << error;
  error = errorFor(R"({"obj": "t.obj", "name": "pane", "glass": {"transmittance": [1.5, 0.9, 0.9]}})");
  EXPECT_NE(error.find("glass transmittance [1.5, 0.9, 0.9] must lie within [0, 1]"), std::string::npos) << error;
}

}  // namespace
}  // namespace portico

namespace portico {
namespace {

// An IES file of 1000 cd all around: 4 pi 1000 lm.
const char* const kIsotropicIes =
    "IESNA:LM-63-2002\n[TEST] isotropic\nTILT=NONE\n1 -1 1 3 1 1 2 0 0 0\n1 1 10\n0 90 180\n0\n1000 1000 1000\n";

TEST(BuildingImportPhotometric, AnObjectsLumensSpreadOverItsArea) {
  TempDirectory temp;
  BrokenBuilding building(temp);
  importBuilding({building.json({{"\"emission\": [10, 10, 10]", "\"lumens\": 1000, \"colour_temperature\": 3000"}})},
                 temp / "store");
  const SceneStore store = SceneStore::open(temp / "store");
  ASSERT_EQ(store.lights().size(), 1u);
  // lamp.obj is a 1 m^2 square: L = Phi / (pi A).
  EXPECT_EQ(store.lights()[0].radiance, radianceOfLumens(1000, colourOfTemperature(3000), 1.0));
  EXPECT_NEAR(lumensOfPower(store.lights()[0].power()), 1000.0, 1e-3);
  EXPECT_GT(store.lights()[0].radiance.x, store.lights()[0].radiance.z);   // warm
}

TEST(BuildingImportPhotometric, AnIesLuminaireIsAPointLightKeptWithItsDistribution) {
  TempDirectory temp;
  writeText(temp.path() / "lamp.ies", kIsotropicIes);
  BrokenBuilding building(temp);
  const std::string lights =
      R"("lights": [{"name": "bulb", "cell": "room", "ies": "lamp.ies", "position": [1, 1.5, 1], "lumens": 800,
                     "colour": [1, 1, 1]},
                    {"name": "bulb 2", "cell": "hall", "ies": "lamp.ies", "position": [3, 1.5, 1],
                     "aim": [1, 0, 0]}],
  "camera")";
  importBuilding({building.json({{"\"camera\"", lights}})}, temp / "store");
  const SceneStore store = SceneStore::open(temp / "store");
  ASSERT_EQ(store.lights().size(), 3u);
  const AreaLight& bulb = store.lights()[1];
  ASSERT_TRUE(bulb.isPoint());
  ASSERT_TRUE(bulb.intensity);
  EXPECT_EQ(bulb.cell, 0u);
  EXPECT_EQ(bulb.corner, Vec3(1, 1.5f, 1));
  EXPECT_EQ(bulb.edge1, Vec3(0, -1, 0));
  EXPECT_EQ(bulb.edge2, Vec3(1, 0, 0));
  EXPECT_NEAR(bulb.intensity->lumens(), 4 * M_PI * 1000, 1e-6 * 4 * M_PI * 1000);
  // Scaled to the 800 lm asked for.
  EXPECT_NEAR(lumensOfPower(bulb.power()), 800, 1e-3);
  // Both luminaires share one distribution in the store.
  EXPECT_EQ(store.lights()[2].intensity.get(), bulb.intensity.get());
  // Aimed along +x: C0 defaults to +z.
  EXPECT_EQ(store.lights()[2].edge2, Vec3(0, 0, 1));
  EXPECT_NEAR(lumensOfPower(store.lights()[2].power()), 4 * M_PI * 1000, 1e-2);
  // A re-cut into voxels keeps each luminaire, in the voxel holding its point.
  ImportOptions grid;
  grid.gridResolution = 2;
  importBuilding({temp / "store"}, temp / "voxels", grid);
  const SceneStore voxels = SceneStore::open(temp / "voxels");
  int points = 0;
  for (const AreaLight& light : voxels.lights())
    if (light.isPoint()) {
      ++points;
      EXPECT_TRUE(voxels.cells()[light.cell].bounds.contains(light.corner));
      EXPECT_NEAR(light.intensity->lumens(), 4 * M_PI * 1000, 1e-2);
    }
  EXPECT_EQ(points, 2);
}

TEST(BuildingImportPhotometric, BadPhotometricInputGivesOneLineErrors) {
  TempDirectory temp;
  BrokenBuilding building(temp);
  const auto withLight = [&](const std::string& light) {
    return building.importError({{"\"camera\"", "\"lights\": [" + light + "], \"camera\""}});
  };
  writeText(temp.path() / "lamp.ies", kIsotropicIes);
  std::string truncated = kIsotropicIes;
  writeText(temp.path() / "short.ies", truncated.substr(0, truncated.size() - 6));
  const std::string path = (temp.path() / "building.json").string();
  EXPECT_EQ(withLight(R"({"name": "b", "cell": "room", "ies": "short.ies", "position": [1, 1, 1]})"),
            path + ": lights[0] ('b'): " + (temp.path() / "short.ies").string() +
                ": line 8: the file ends before candela value 3 of 3 (horizontal angle 0, vertical angle 180) "
                "(truncated?)");
  EXPECT_EQ(withLight(R"({"name": "b", "cell": "room", "ies": "none.ies", "position": [1, 1, 1]})"),
            path + ": lights[0] ('b'): " + (temp.path() / "none.ies").string() + ": cannot be read");
  EXPECT_EQ(withLight(R"({"name": "b", "cell": "room", "ies": "lamp.ies", "position": [1, 3, 1]})"),
            path + ": lights[0] ('b'): position (1, 3, 1) lies outside the aabb of its cell 'room'");
  EXPECT_EQ(withLight(R"({"name": "b", "cell": "room", "ies": "lamp.ies", "position": [1, 1, 1], "c0": [0, 2, 0]})"),
            path + ": lights[0] ('b'): c0 is parallel to aim; it must point across it");
  EXPECT_EQ(withLight(R"({"name": "b", "cell": "room", "ies": "lamp.ies", "position": [1, 1, 1], "aim": [0, 0, 0]})"),
            path + ": lights[0] ('b') aim is a zero vector; it gives a direction");
  const std::string quad = R"("quad": {"corner": [0.5, 1.9, 0.5], "edge1": [1, 0, 0], "edge2": [0, 0, 1]})";
  EXPECT_EQ(withLight(R"({"name": "p", "cell": "room", "radiance": [1, 1, 1], "lumens": 10, )" + quad + "}"),
            path + ": lights[0] ('p'): give \"radiance\" or \"lumens\", not both");
  EXPECT_EQ(withLight(R"({"name": "p", "cell": "room", "radiance": [1, 1, 1], "colour_temperature": 3000, )" + quad + "}"),
            path + ": lights[0] ('p'): \"colour_temperature\" needs \"lumens\" (the lamp's luminous flux)");
  EXPECT_EQ(withLight(R"({"name": "p", "cell": "room", "lumens": 10, "colour_temperature": 1000, )" + quad + "}"),
            path + ": lights[0] ('p'): colour temperature 1000 K lies outside 1667-25000 K");
  EXPECT_EQ(withLight(R"({"name": "p", "cell": "room", "lumens": -5, )" + quad + "}"),
            path + ": lights[0] ('p'): lumens = -5 must be above 0");
  EXPECT_EQ(withLight(R"({"name": "p", "cell": "room", "lumens": 10, "colour": [0, 0, 0], )" + quad + "}"),
            path + ": lights[0] ('p'): colour [0, 0, 0] must not be negative or black");
  EXPECT_EQ(building.importError({{"\"emission\": [10, 10, 10]", "\"emission\": [10, 10, 10], \"lumens\": 5"}}),
            path + ": objects[1] ('lamp'): give \"emission\" (radiance) or \"lumens\", not both");
}

}  // namespace
}  // namespace portico
