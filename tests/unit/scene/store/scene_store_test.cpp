// The scene store: SceneStoreWriter -> scene.db + cell files -> SceneStore
// and CellGeometry, and the errors on the way.
#include "common/scene/store/scene_store.h"

#include <capnp/message.h>
#include <capnp/serialize.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <stdexcept>

#include "common/scene/store/cell_geometry.h"
#include "common/util/sqlite.h"
#include "proto/scene.capnp.h"
#include "tests/unit/scene/scene_test_support.h"

namespace portico {
namespace {

namespace fs = std::filesystem;
using testing_support::hasEntryStartingWith;
using testing_support::TempDirectory;

// Runs `action` and returns the std::runtime_error's message ("" if none).
template <typename Action>
std::string errorOf(Action&& action) {
  try {
    action();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

// A tiny hand-made store: a room with a floor and a light, a hall with one
// triangle, and an empty sky above both holding the camera.
struct TinyScene {
  std::vector<CellContent> cells;
  std::vector<std::pair<uint32_t, uint32_t>> portalCells;
  std::vector<std::vector<Vec3>> portalPolygons;
  AreaLight light;
  Camera camera;
  bool whiteIsGlass = false;   // material 0 thin glass
  std::optional<SiteLocation> site;   // where it stands
  std::vector<Camera> extraCameras;   // named cameras beside the default

  TinyScene() {
    CellContent room;
    room.id = 0;
    room.name = "room";
    room.bounds = Bounds3(Vec3(0, 0, 0), Vec3(2, 2, 2));
    room.positions = {0, 0, 0, 2, 0, 0, 2, 0, 2, 0, 0, 2,                       // floor
                      0.5f, 1.9f, 0.5f, 1.5f, 1.9f, 0.5f, 1.5f, 1.9f, 1.5f, 0.5f, 1.9f, 1.5f};  // light
    room.indices = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7};
    room.materials = {0, 0, 1, 1};
    CellContent hall;
    hall.id = 1;
    hall.name = "hall";
    hall.bounds = Bounds3(Vec3(2, 0, 0), Vec3(4, 2, 2));
    hall.positions = {2, 0, 0, 4, 0, 0, 4, 0, 1.75f};
    hall.indices = {0, 2, 1};
    hall.materials = {0};
    CellContent sky;
    sky.id = 2;
    sky.name = "sky";
    sky.bounds = Bounds3(Vec3(0, 2, 0), Vec3(4, 3, 2));
    cells = {room, hall, sky};
    portalCells = {{0, 1}, {0, 2}, {1, 2}};
    portalPolygons = {{Vec3(2, 0, 0.5f), Vec3(2, 0, 1.5f), Vec3(2, 1.5f, 1.5f), Vec3(2, 1.5f, 0.5f)},
                      {Vec3(0, 2, 0), Vec3(2, 2, 0), Vec3(2, 2, 2), Vec3(0, 2, 2)},
                      {Vec3(2, 2, 0), Vec3(4, 2, 0), Vec3(4, 2, 2), Vec3(2, 2, 2)}};
    light.cell = 0;
    light.corner = Vec3(0.5f, 1.9f, 0.5f);
    light.edge1 = Vec3(1, 0, 0);
    light.edge2 = Vec3(0, 0, 1);
    light.radiance = Vec3(12, 11, 9.5f);
    camera.origin = Vec3(2, 2.5f, 1);
    camera.target = Vec3(1, 0, 1);
    camera.up = Vec3(0, 0, 1);
    camera.fovYDegrees = 50;
    camera.width = 64;
    camera.height = 48;
    camera.cell = 2;
  }

  // Writes the store; cells in a scrambled order, as any order is allowed.
  void write(const std::string& directory, uint64_t maxChunkElements = 0) const {
    SceneStoreWriter writer(directory);
    if (maxChunkElements) writer.setMaxChunkElements(maxChunkElements);
    writer.setMeta("generator", "tiny-test");
    writer.addMaterial("white", Vec3(0.8f, 0.8f, 0.8f));
    writer.addMaterial("lamp", Vec3(0), Vec3(12, 11, 9.5f), /*hiddenFromCamera=*/true);
    if (whiteIsGlass) writer.setMaterialGlass(0, Vec3(0.7f, 0.8f, 0.9f), 1.52f);
    for (size_t i = 0; i < portalCells.size(); ++i)
      writer.addPortal(portalCells[i].first, portalCells[i].second, portalPolygons[i]);
    writer.addLight(light);
    writer.setCamera(camera);
    for (const Camera& extra : extraCameras) writer.addCamera(extra);
    if (site) writer.setSite(*site);
    for (uint32_t id : {2u, 0u, 1u}) writer.writeCell(cells[id]);
    writer.commit();
  }
};

void expectSameVec3(const Vec3& actual, const Vec3& expected) {
  EXPECT_EQ(actual.x, expected.x);
  EXPECT_EQ(actual.y, expected.y);
  EXPECT_EQ(actual.z, expected.z);
}

void expectCellMatches(const CellGeometry& geometry, const CellContent& cell) {
  EXPECT_EQ(geometry.id(), cell.id);
  expectSameVec3(geometry.bounds().lo, cell.bounds.lo);
  expectSameVec3(geometry.bounds().hi, cell.bounds.hi);
  const MeshView& mesh = geometry.mesh();
  ASSERT_EQ(mesh.vertexCount * 3, cell.positions.size());
  ASSERT_EQ(mesh.triangleCount * 3, cell.indices.size());
  for (size_t i = 0; i < cell.positions.size(); ++i) EXPECT_EQ(mesh.positions[i], cell.positions[i]) << i;
  for (size_t i = 0; i < cell.indices.size(); ++i) EXPECT_EQ(mesh.indices[i], cell.indices[i]) << i;
  for (uint32_t t = 0; t < cell.materials.size(); ++t) EXPECT_EQ(geometry.material(t), cell.materials[t]) << t;
}

TEST(SceneStore, RoundTripsEveryRecordExactly) {
  TempDirectory temp;
  const TinyScene scene;
  scene.write(temp / "store");
  const SceneStore store = SceneStore::open(temp / "store");

  ASSERT_EQ(store.cells().size(), 3u);
  for (const CellContent& cell : scene.cells) {
    const CellInfo& info = store.cells()[cell.id];
    EXPECT_EQ(info.id, cell.id);
    EXPECT_EQ(info.name, cell.name);
    expectSameVec3(info.bounds.lo, cell.bounds.lo);
    expectSameVec3(info.bounds.hi, cell.bounds.hi);
    EXPECT_EQ(info.triangleCount, cell.indices.size() / 3);
    EXPECT_EQ(info.byteCount, fs::file_size(store.cellPath(cell.id)));
    EXPECT_EQ(info.file, "cells/" + std::to_string(cell.id) + ".cell");
  }
  EXPECT_EQ(store.totalTriangles(), 5u);

  ASSERT_EQ(store.portals().size(), scene.portalCells.size());
  for (uint32_t p = 0; p < store.portals().size(); ++p) {
    const Portal& portal = store.portals()[p];
    EXPECT_EQ(portal.id, p);
    EXPECT_EQ(portal.cellA, scene.portalCells[p].first);
    EXPECT_EQ(portal.cellB, scene.portalCells[p].second);
    EXPECT_EQ(portal.polygon, scene.portalPolygons[p]);
  }

  ASSERT_EQ(store.materials().size(), 2u);
  EXPECT_EQ(store.materials()[0].name, "white");
  expectSameVec3(store.materials()[0].albedo, Vec3(0.8f));
  EXPECT_FALSE(store.materials()[0].emissive());
  EXPECT_FALSE(store.materials()[0].hiddenFromCamera);
  EXPECT_EQ(store.materials()[1].name, "lamp");
  expectSameVec3(store.materials()[1].emission, Vec3(12, 11, 9.5f));
  EXPECT_TRUE(store.materials()[1].hiddenFromCamera);

  ASSERT_EQ(store.lights().size(), 1u);
  const AreaLight& light = store.lights()[0];
  EXPECT_EQ(light.id, 0u);
  EXPECT_EQ(light.cell, scene.light.cell);
  expectSameVec3(light.corner, scene.light.corner);
  expectSameVec3(light.edge1, scene.light.edge1);
  expectSameVec3(light.edge2, scene.light.edge2);
  expectSameVec3(light.radiance, scene.light.radiance);

  ASSERT_EQ(store.cameras().size(), 1u);
  const Camera& camera = store.camera();
  EXPECT_EQ(camera.name, "default");
  expectSameVec3(camera.origin, scene.camera.origin);
  expectSameVec3(camera.target, scene.camera.target);
  expectSameVec3(camera.up, scene.camera.up);
  EXPECT_EQ(camera.fovYDegrees, scene.camera.fovYDegrees);
  EXPECT_EQ(camera.width, scene.camera.width);
  EXPECT_EQ(camera.height, scene.camera.height);
  EXPECT_EQ(camera.cell, scene.camera.cell);

  EXPECT_EQ(store.meta().at("generator"), "tiny-test");
  EXPECT_EQ(store.meta().at("format_version"), "9");
  EXPECT_FALSE(store.materials()[0].glass());
  EXPECT_FALSE(store.site());

  for (const CellContent& cell : scene.cells) {
    const auto geometry = CellGeometry::load(store.cellPath(cell.id), cell.id, store.materials().size());
    expectCellMatches(*geometry, cell);
    // The cell file lists exactly the catalogue's portals touching the cell.
    std::vector<const Portal*> expected;
    for (const Portal& portal : store.portals())
      if (portal.cellA == cell.id || portal.cellB == cell.id) expected.push_back(&portal);
    ASSERT_EQ(geometry->portals().size(), expected.size());
    for (size_t i = 0; i < expected.size(); ++i) {
      const CellPortalView& view = geometry->portals()[i];
      EXPECT_EQ(view.portalId, expected[i]->id);
      EXPECT_EQ(view.neighborCell, expected[i]->cellA == cell.id ? expected[i]->cellB : expected[i]->cellA);
      EXPECT_EQ(view.polygon, expected[i]->polygon);
    }
  }
}

TEST(SceneStore, LocatesThePointsSmallestContainingCell) {
  TempDirectory temp;
  TinyScene().write(temp / "store");
  const SceneStore store = SceneStore::open(temp / "store");
  EXPECT_EQ(store.locateCell(Vec3(1, 1, 1)), 0u);
  EXPECT_EQ(store.locateCell(Vec3(3, 1, 1)), 1u);
  EXPECT_EQ(store.locateCell(Vec3(1, 2.5f, 1)), 2u);
  EXPECT_EQ(store.locateCell(store.camera().origin), store.camera().cell);
  // On the shared face x = 2 both rooms contain the point: equal volumes, smaller id.
  EXPECT_EQ(store.locateCell(Vec3(2, 1, 1)), 0u);
  EXPECT_EQ(store.locateCell(Vec3(9, 9, 9)), std::nullopt);
}

TEST(CellGeometry, SingleChunkArraysAreReadInPlace) {
  TempDirectory temp;
  const TinyScene scene;
  scene.write(temp / "store");
  const SceneStore store = SceneStore::open(temp / "store");
  const auto geometry = CellGeometry::load(store.cellPath(0), 0, store.materials().size());
  EXPECT_TRUE(geometry->readInPlace());
  EXPECT_EQ(geometry->bytes(), store.cells()[0].byteCount);
  expectCellMatches(*geometry, scene.cells[0]);
}

TEST(CellGeometry, ArraysSplitOverChunksAreJoined) {
  TempDirectory temp;
  const TinyScene scene;
  scene.write(temp / "store", 6);   // two vertices or two triangles per chunk
  const SceneStore store = SceneStore::open(temp / "store");
  const auto geometry = CellGeometry::load(store.cellPath(0), 0, store.materials().size());
  EXPECT_FALSE(geometry->readInPlace());
  expectCellMatches(*geometry, scene.cells[0]);
  const auto sky = CellGeometry::load(store.cellPath(2), 2, store.materials().size());
  EXPECT_EQ(sky->mesh().triangleCount, 0u);
  EXPECT_EQ(sky->mesh().vertexCount, 0u);
}

// The reader's traversal limit is about twice the file's size, which holds
// only if every bulk array is walked once: a big cell (where the limit's
// constant slack does not hide a second pass) must load, chunked or not.
TEST(CellGeometry, LargeCellsLoadWithinTheTraversalLimit) {
  CellContent cell;
  cell.id = 0;
  cell.name = "big";
  cell.bounds = Bounds3(Vec3(0), Vec3(1));
  const uint32_t vertexCount = 60000;
  for (uint32_t i = 0; i < vertexCount; ++i)
    cell.positions.insert(cell.positions.end(), {float(i % 97) / 97, float(i % 89) / 89, float(i % 83) / 83});
  for (uint32_t t = 0; t < vertexCount; ++t) {
    cell.indices.insert(cell.indices.end(), {t, (t + 1) % vertexCount, (t + 7) % vertexCount});
    cell.materials.push_back(t % 2);
  }
  for (uint64_t chunkElements : {uint64_t{0}, uint64_t{30000}}) {
    TempDirectory temp;
    {
      SceneStoreWriter writer(temp / "store");
      if (chunkElements) writer.setMaxChunkElements(chunkElements);
      writer.addMaterial("a", Vec3(0.5f));
      writer.addMaterial("b", Vec3(0.25f));
      writer.writeCell(cell);
      Camera camera;
      camera.origin = Vec3(0.5f);
      camera.target = Vec3(0.5f, 0.5f, 1);
      writer.setCamera(camera);
      writer.commit();
    }
    const auto geometry = CellGeometry::load(SceneStore::open(temp / "store").cellPath(0), 0, 2);
    EXPECT_EQ(geometry->readInPlace(), chunkElements == 0);
    expectCellMatches(*geometry, cell);
  }
}

TEST(SceneStoreWriter, ReplacesAnEarlierStoreButNothingElse) {
  TempDirectory temp;
  TinyScene scene;
  scene.write(temp / "store");
  scene.cells[1].name = "renamed-hall";
  scene.write(temp / "store");
  EXPECT_EQ(SceneStore::open(temp / "store").cells()[1].name, "renamed-hall");
  EXPECT_FALSE(hasEntryStartingWith(temp.path(), "store."));   // no staging or old copy left

  fs::create_directories(temp / "precious");
  std::ofstream(temp / "precious/notes.txt") << "keep me";
  const std::string error = errorOf([&] { scene.write(temp / "precious"); });
  EXPECT_NE(error.find("precious"), std::string::npos) << error;
  EXPECT_NE(error.find("not a scene store"), std::string::npos) << error;
  EXPECT_TRUE(fs::exists(temp / "precious/notes.txt"));
}

// Each broken scene must fail with a message naming the culprit, and leave
// neither the store nor its staging directory behind.
void expectRejected(const std::function<void(SceneStoreWriter&)>& build, const std::vector<std::string>& phrases) {
  TempDirectory temp;
  const std::string directory = temp / "store";
  const std::string error = errorOf([&] {
    SceneStoreWriter writer(directory);
    build(writer);
    writer.commit();
  });
  ASSERT_FALSE(error.empty()) << "accepted a broken scene";
  for (const std::string& phrase : phrases) EXPECT_NE(error.find(phrase), std::string::npos) << error;
  EXPECT_EQ(error.find('\n'), std::string::npos) << "one line: " << error;
  EXPECT_FALSE(fs::exists(directory));
  EXPECT_FALSE(hasEntryStartingWith(temp.path(), "store"));
}

// A valid scene's parts, for the rejection tests to break one at a time.
CellContent triangleCell(uint32_t id, uint32_t material = 0) {
  CellContent cell;
  cell.id = id;
  cell.name = "cell-" + std::to_string(id);
  cell.bounds = Bounds3(Vec3(float(id), 0, 0), Vec3(float(id) + 1, 1, 1));
  cell.positions = {float(id), 0, 0, float(id) + 1, 0, 0, float(id), 0, 1};
  cell.indices = {0, 2, 1};
  cell.materials = {material};
  return cell;
}
Camera cameraIn(uint32_t cell) {
  Camera camera;
  camera.origin = Vec3(float(cell) + 0.5f, 0.5f, 0.5f);
  camera.target = camera.origin + Vec3(0, 0, 1);
  camera.cell = cell;
  return camera;
}
const std::vector<Vec3> kSharedFace{Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(1, 1, 1), Vec3(1, 0, 1)};

TEST(SceneStoreWriter, RejectsAPortalToAnUnwrittenCell) {
  expectRejected(
      [](SceneStoreWriter& writer) {
        writer.addMaterial("grey", Vec3(0.5f));
        writer.addPortal(0, 5, kSharedFace);
        writer.writeCell(triangleCell(0));
        writer.setCamera(cameraIn(0));
      },
      {"portal 0", "cell 5 was never written"});
}

TEST(SceneStoreWriter, RejectsAMissingMaterial) {
  expectRejected(
      [](SceneStoreWriter& writer) {
        writer.addMaterial("grey", Vec3(0.5f));
        writer.writeCell(triangleCell(0, 3));
        writer.setCamera(cameraIn(0));
      },
      {"cell 0 ('cell-0')", "material 3", "1 materials"});
}

TEST(SceneStoreWriter, RejectsANonFinitePosition) {
  expectRejected(
      [](SceneStoreWriter& writer) {
        writer.addMaterial("grey", Vec3(0.5f));
        CellContent cell = triangleCell(0);
        cell.positions[4] = std::numeric_limits<float>::quiet_NaN();
        writer.writeCell(cell);
        writer.setCamera(cameraIn(0));
      },
      {"cell 0 ('cell-0')", "vertex 1", "not finite"});
}

TEST(SceneStoreWriter, RejectsAGapInCellIds) {
  expectRejected(
      [](SceneStoreWriter& writer) {
        writer.addMaterial("grey", Vec3(0.5f));
        writer.writeCell(triangleCell(0));
        writer.writeCell(triangleCell(2));
        writer.setCamera(cameraIn(0));
      },
      {"cell 1 was never written"});
}

TEST(SceneStoreWriter, RejectsAnIndexOutOfRange) {
  expectRejected(
      [](SceneStoreWriter& writer) {
        CellContent cell = triangleCell(0);
        cell.indices[1] = 3;
        writer.writeCell(cell);
      },
      {"cell 0 ('cell-0')", "triangle 0 uses vertex 3", "3 vertices"});
}

TEST(SceneStoreWriter, RejectsALightOrCameraInAnUnwrittenCell) {
  expectRejected(
      [](SceneStoreWriter& writer) {
        writer.addMaterial("grey", Vec3(0.5f));
        AreaLight light;
        light.cell = 4;
        light.edge1 = Vec3(1, 0, 0);
        light.edge2 = Vec3(0, 0, -1);
        light.radiance = Vec3(1);
        writer.addLight(light);
        writer.writeCell(triangleCell(0));
        writer.setCamera(cameraIn(0));
      },
      {"light 0", "cell 4 was never written"});
  expectRejected(
      [](SceneStoreWriter& writer) {
        writer.addMaterial("grey", Vec3(0.5f));
        writer.writeCell(triangleCell(0));
        writer.setCamera(cameraIn(1));
      },
      {"camera 'default'", "cell 1 was never written"});
}

TEST(SceneStoreWriter, RejectsAPortalAddedAfterItsCell) {
  expectRejected(
      [](SceneStoreWriter& writer) {
        writer.writeCell(triangleCell(0));
        writer.addPortal(0, 1, kSharedFace);
      },
      {"portal 0", "already written"});
}

TEST(SceneStoreWriter, RejectsANonPlanarPortal) {
  expectRejected(
      [](SceneStoreWriter& writer) {
        writer.addPortal(0, 1, {Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(1.5f, 1, 1), Vec3(1, 0, 1)});
      },
      {"portal 0", "not planar"});
}

TEST(SceneStore, OpenNamesTheMissingCatalogue) {
  TempDirectory temp;
  const std::string missing = errorOf([&] { SceneStore::open(temp / "nowhere"); });
  EXPECT_NE(missing.find("nowhere"), std::string::npos) << missing;
  const std::string empty = errorOf([&] { SceneStore::open(temp.path().string()); });
  EXPECT_NE(empty.find(temp.path().string()), std::string::npos) << empty;
  EXPECT_NE(empty.find("no scene.db"), std::string::npos) << empty;
}

TEST(SceneStore, OpenRejectsAnUnknownSchemaVersion) {
  TempDirectory temp;
  TinyScene().write(temp / "store");
  sql::Database(temp / "store/scene.db", sql::Database::Mode::ReadWriteCreate).setUserVersion(99);
  const std::string error = errorOf([&] { SceneStore::open(temp / "store"); });
  EXPECT_NE(error.find(temp / "store"), std::string::npos) << error;
  EXPECT_NE(error.find("schema version 99"), std::string::npos) << error;
}

// A store as version 3 wrote it: one camera, in table camera.
void keepOnlyTheDefaultCameraAsVersionThreeDid(sql::Database& db) {
  db.exec(R"sql(
    CREATE TABLE camera(
      id INTEGER PRIMARY KEY CHECK (id = 0),
      origin_x REAL NOT NULL, origin_y REAL NOT NULL, origin_z REAL NOT NULL,
      target_x REAL NOT NULL, target_y REAL NOT NULL, target_z REAL NOT NULL,
      up_x REAL NOT NULL, up_y REAL NOT NULL, up_z REAL NOT NULL,
      fov_y_deg REAL NOT NULL, width INTEGER NOT NULL, height INTEGER NOT NULL,
      cell INTEGER NOT NULL REFERENCES cells(id));
    INSERT INTO camera SELECT 0, origin_x, origin_y, origin_z, target_x, target_y, target_z, up_x, up_y, up_z,
                              fov_y_deg, width, height, cell FROM cameras WHERE id = 0;
    DROP TABLE cameras;)sql");
  db.setUserVersion(3);
}

// Several named cameras: the default first, the others in the order added,
// every field exact; found by name.
TEST(SceneStore, RoundTripsSeveralNamedCameras) {
  TempDirectory temp;
  TinyScene scene;
  scene.camera.name = "overview";
  Camera inRoom = scene.camera;
  inRoom.name = "room-door";
  inRoom.origin = Vec3(0.25f, 1.6f, 1.0f / 3.0f);
  inRoom.target = Vec3(1.9f, 1.2f, 1.0f);
  inRoom.up = Vec3(0, 1, 0);
  inRoom.fovYDegrees = 61.5f;
  inRoom.width = 32;
  inRoom.height = 24;
  inRoom.cell = 0;
  Camera inHall = inRoom;
  inHall.name = "hall end";
  inHall.origin = Vec3(3.5f, 1.6f, 1.0f);
  inHall.cell = 1;
  scene.extraCameras = {inRoom, inHall};
  scene.write(temp / "store");

  const SceneStore store = SceneStore::open(temp / "store");
  ASSERT_EQ(store.cameras().size(), 3u);
  const Camera* expected[] = {&scene.camera, &inRoom, &inHall};
  for (size_t k = 0; k < 3; ++k) {
    const Camera& camera = store.cameras()[k];
    EXPECT_EQ(camera.name, expected[k]->name);
    expectSameVec3(camera.origin, expected[k]->origin);
    expectSameVec3(camera.target, expected[k]->target);
    expectSameVec3(camera.up, expected[k]->up);
    EXPECT_EQ(camera.fovYDegrees, expected[k]->fovYDegrees);
    EXPECT_EQ(camera.width, expected[k]->width);
    EXPECT_EQ(camera.height, expected[k]->height);
    EXPECT_EQ(camera.cell, expected[k]->cell);
    EXPECT_EQ(store.findCamera(expected[k]->name), &camera);
  }
  EXPECT_EQ(store.camera().name, "overview");
  EXPECT_EQ(store.findCamera("nobody"), nullptr);
}

// A store written before cameras had names is read as one camera, "default".
TEST(SceneStore, OpensAVersionThreeStoreAsOneCameraNamedDefault) {
  TempDirectory temp;
  TinyScene scene;
  Camera inRoom = scene.camera;
  inRoom.name = "room";
  inRoom.origin = Vec3(1, 1, 1);
  inRoom.cell = 0;
  scene.extraCameras = {inRoom};
  scene.write(temp / "store");
  {
    sql::Database db(temp / "store/scene.db", sql::Database::Mode::ReadWriteCreate);
    keepOnlyTheDefaultCameraAsVersionThreeDid(db);
  }
  const SceneStore store = SceneStore::open(temp / "store");
  ASSERT_EQ(store.cameras().size(), 1u);
  EXPECT_EQ(store.camera().name, "default");
  expectSameVec3(store.camera().origin, scene.camera.origin);
  expectSameVec3(store.camera().target, scene.camera.target);
  EXPECT_EQ(store.camera().cell, scene.camera.cell);
  EXPECT_EQ(store.findCamera("default"), &store.camera());
}

TEST(SceneStoreWriter, RejectsCamerasWithoutAUsableName) {
  const auto writeWith = [](Camera extra) {
    TempDirectory temp;
    TinyScene scene;
    scene.extraCameras = {extra};
    return errorOf([&] { scene.write(temp / "store"); });
  };
  Camera camera = TinyScene().camera;
  camera.name = "default";
  std::string error = writeWith(camera);
  EXPECT_NE(error.find("camera 'default': the name is used twice"), std::string::npos) << error;
  camera.name = "";
  error = writeWith(camera);
  EXPECT_NE(error.find("needs a name"), std::string::npos) << error;
  camera.name = "tab\there";
  error = writeWith(camera);
  EXPECT_NE(error.find("control character"), std::string::npos) << error;
  camera.name = "far";
  camera.origin = Vec3(50, 1, 1);
  error = writeWith(camera);
  EXPECT_NE(error.find("camera 'far': origin (50, 1, 1) lies outside the bounds of its cell 2 ('sky')"),
            std::string::npos)
      << error;
}

// Glass (schema 6) round-trips; a version 5 store has none.
TEST(SceneStore, RoundTripsGlassAndReadsAVersionFiveStoreWithout) {
  TempDirectory temp;
  TinyScene scene;
  scene.whiteIsGlass = true;
  scene.write(temp / "store");
  {
    const SceneStore store = SceneStore::open(temp / "store");
    ASSERT_TRUE(store.materials()[0].glass());
    expectSameVec3(store.materials()[0].transmittance, Vec3(0.7f, 0.8f, 0.9f));
    EXPECT_EQ(store.materials()[0].ior, 1.52f);
    EXPECT_FALSE(store.materials()[1].glass());
  }
  {
    sql::Database db(temp / "store/scene.db", sql::Database::Mode::ReadWriteCreate);
    for (const char* column : {"transmittance_r", "transmittance_g", "transmittance_b", "ior"})
      db.exec(std::string("ALTER TABLE materials DROP COLUMN ") + column);
    db.setUserVersion(5);
  }
  const SceneStore store = SceneStore::open(temp / "store");
  EXPECT_FALSE(store.materials()[0].glass());
  EXPECT_EQ(store.materials()[0].ior, 1.5f);
}

// The site (schema 7) round-trips exactly; a version 6 store has none.
TEST(SceneStore, RoundTripsTheSiteAndReadsAVersionSixStoreWithout) {
  TempDirectory temp;
  TinyScene scene;
  scene.site = SiteLocation{49.1003, 8.4366, -12.5};
  scene.write(temp / "store");
  {
    const SceneStore store = SceneStore::open(temp / "store");
    ASSERT_TRUE(store.site());
    EXPECT_EQ(*store.site(), *scene.site);   // doubles, bit for bit
  }
  {
    sql::Database db(temp / "store/scene.db", sql::Database::Mode::ReadWriteCreate);
    db.exec("DROP TABLE site");
    db.setUserVersion(6);
  }
  EXPECT_FALSE(SceneStore::open(temp / "store").site());
}

TEST(SceneStore, RefusesASiteOffTheEarthNamingTheValue) {
  TempDirectory temp;
  SceneStoreWriter writer(temp / "store");
  const std::string error = errorOf([&] { writer.setSite(SiteLocation{91, 8, 0}); });
  EXPECT_NE(error.find("site: latitude 91 must be a number of degrees from -90 to 90"), std::string::npos) << error;
  // A catalogue edited by hand is refused on reading too.
  TinyScene scene;
  scene.site = SiteLocation{10, 20, 0};
  scene.write(temp / "good");
  sql::Database(temp / "good/scene.db", sql::Database::Mode::ReadWriteCreate).exec("UPDATE site SET longitude = 200");
  const std::string read = errorOf([&] { SceneStore::open(temp / "good"); });
  EXPECT_NE(read.find("table site: longitude 200 must be"), std::string::npos) << read;
}

TEST(SceneStore, RefusesGlassThatMakesLight) {
  TempDirectory temp;
  SceneStoreWriter writer(temp / "store");
  writer.addMaterial("pane", Vec3(0));
  try {
    writer.setMaterialGlass(0, Vec3(1.2f, 0.5f, 0.5f), 1.5f);
    FAIL() << "a transmittance above 1 was taken";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("material 0 ('pane'): glass transmittance"), std::string::npos) << e.what();
  }
}

// A point luminaire keeps its luminous opening (LM-63's width, length and
// height, as given); a store of version 8, before openings were kept, reads
// every luminaire as a point no camera sees.
TEST(SceneStore, KeepsALuminairesOpeningAndReadsVersionEightsAsPoints) {
  TempDirectory temp;
  TinyScene scene;
  scene.light.shape = LightShape::Point;
  scene.light.corner = Vec3(1, 1.9f, 1);
  scene.light.edge1 = Vec3(0, -1, 0);
  scene.light.edge2 = Vec3(1, 0, 0);
  scene.light.radiance = Vec3(1.0f / 179);
  scene.light.intensity = std::make_shared<const LuminousIntensity>(
      CandelaGrid{{0, 90}, {0}, {100, 50}}, "lamp.ies");
  scene.light.opening = LuminousOpening::fromLm63(-0.2, 0.6, -0.2);   // a tube along C0
  scene.write(temp / "store");
  const AreaLight read = SceneStore::open(temp / "store").lights().at(0);
  EXPECT_EQ(read.opening.width(), -0.2);
  EXPECT_EQ(read.opening.length(), 0.6);
  EXPECT_EQ(read.opening.height(), -0.2);
  EXPECT_EQ(read.opening.shape(), LuminousOpening::Shape::Cylinder);
  EXPECT_TRUE(read.seenAsOpening());
  {
    sql::Database db(temp / "store/scene.db", sql::Database::Mode::ReadWriteCreate);
    for (const char* column : {"opening_width", "opening_length", "opening_height"})
      db.exec(std::string("ALTER TABLE point_lights DROP COLUMN ") + column);
    db.setUserVersion(8);
  }
  const AreaLight old = SceneStore::open(temp / "store").lights().at(0);
  EXPECT_EQ(old.opening.shape(), LuminousOpening::Shape::None);
  EXPECT_FALSE(old.seenAsOpening());
  EXPECT_NEAR(old.intensity->lumens(), read.intensity->lumens(), 1e-9);
  // An opening of no LM-63 shape, written by hand, is refused naming the light.
  {
    sql::Database db(temp / "store/scene.db", sql::Database::Mode::ReadWriteCreate);
    db.exec("ALTER TABLE point_lights ADD COLUMN opening_width REAL NOT NULL DEFAULT -1");
    db.exec("ALTER TABLE point_lights ADD COLUMN opening_length REAL NOT NULL DEFAULT 1");
    db.exec("ALTER TABLE point_lights ADD COLUMN opening_height REAL NOT NULL DEFAULT 0");
    db.setUserVersion(9);
  }
  const std::string error = errorOf([&] { SceneStore::open(temp / "store"); });
  EXPECT_NE(error.find("light 0: the luminous opening (width -1, length 1, height 0) is none of"), std::string::npos)
      << error;
}

// Version 1 (before materials.hidden_from_camera) is still read: nothing hidden.
TEST(SceneStore, OpensAVersionOneStoreWithNothingHidden) {
  TempDirectory temp;
  TinyScene().write(temp / "store");
  {
    sql::Database db(temp / "store/scene.db", sql::Database::Mode::ReadWriteCreate);
    EXPECT_EQ(db.userVersion(), 9);
    db.exec("DROP TABLE point_lights");
    db.exec("DROP TABLE light_distributions");
    db.exec("DROP TABLE site");
    db.exec("DROP TABLE material_textures");
    keepOnlyTheDefaultCameraAsVersionThreeDid(db);
    db.exec("ALTER TABLE materials DROP COLUMN hidden_from_camera");
    db.exec("ALTER TABLE lights DROP COLUMN shape");
    db.setUserVersion(1);
  }
  const SceneStore store = SceneStore::open(temp / "store");
  ASSERT_EQ(store.materials().size(), 2u);
  EXPECT_EQ(store.materials()[1].name, "lamp");
  expectSameVec3(store.materials()[1].emission, Vec3(12, 11, 9.5f));
  for (const Material& material : store.materials()) EXPECT_FALSE(material.hiddenFromCamera) << material.name;
  EXPECT_EQ(store.cells().size(), 3u);
  EXPECT_EQ(store.lights().size(), 1u);

  sql::Database(temp / "store/scene.db", sql::Database::Mode::ReadWriteCreate).setUserVersion(0);
  const std::string error = errorOf([&] { SceneStore::open(temp / "store"); });
  EXPECT_NE(error.find("schema version 0"), std::string::npos) << error;
}

// Version 2 (before lights.shape) is still read: every light a parallelogram.
TEST(SceneStore, OpensAVersionTwoStoreWithParallelogramLights) {
  TempDirectory temp;
  TinyScene().write(temp / "store");
  {
    sql::Database db(temp / "store/scene.db", sql::Database::Mode::ReadWriteCreate);
    db.exec("UPDATE lights SET shape = 'triangle'");
  }
  ASSERT_EQ(SceneStore::open(temp / "store").lights().size(), 1u);
  EXPECT_TRUE(SceneStore::open(temp / "store").lights()[0].isTriangle());
  {
    sql::Database db(temp / "store/scene.db", sql::Database::Mode::ReadWriteCreate);
    keepOnlyTheDefaultCameraAsVersionThreeDid(db);
    db.exec("ALTER TABLE lights DROP COLUMN shape");
    db.setUserVersion(2);
  }
  const SceneStore store = SceneStore::open(temp / "store");
  ASSERT_EQ(store.lights().size(), 1u);
  EXPECT_FALSE(store.lights()[0].isTriangle());
  EXPECT_GT(store.lights()[0].area(), 0.0f);
}

TEST(SceneStore, OpenRejectsAFileThatIsNotADatabase) {
  TempDirectory temp;
  fs::create_directories(temp / "store");
  std::ofstream(temp / "store/scene.db") << "definitely not sqlite, but long enough to have a header at all......";
  const std::string error = errorOf([&] { SceneStore::open(temp / "store"); });
  EXPECT_NE(error.find(temp / "store"), std::string::npos) << error;
}

// Corrupt cell files: each must give a std::runtime_error naming the file.
class CorruptCellFile : public ::testing::Test {
 protected:
  void SetUp() override {
    TinyScene().write(temp_ / "store");
    path_ = SceneStore::open(temp_ / "store").cellPath(0);
  }
  void expectLoadFails(const std::string& phrase, uint32_t expectedCell = 0, size_t materials = 2) {
    const std::string error = errorOf([&] { CellGeometry::load(path_, expectedCell, materials); });
    ASSERT_FALSE(error.empty()) << "loaded a corrupt cell file";
    EXPECT_NE(error.find(path_), std::string::npos) << error;
    EXPECT_NE(error.find(phrase), std::string::npos) << error;
  }
  void writeMessage(capnp::MessageBuilder& message) {
    const int fd = ::open(path_.c_str(), O_WRONLY | O_TRUNC);
    ASSERT_GE(fd, 0);
    capnp::writeMessageToFd(fd, message);
    ::close(fd);
  }
  TempDirectory temp_;
  std::string path_;
};

TEST_F(CorruptCellFile, TruncatedToWholeWords) {
  fs::resize_file(path_, fs::file_size(path_) - 64);
  expectLoadFails("malformed message");
}

TEST_F(CorruptCellFile, TruncatedMidWord) {
  fs::resize_file(path_, fs::file_size(path_) - 3);
  expectLoadFails("not a positive multiple of 8");
}

TEST_F(CorruptCellFile, Empty) {
  fs::resize_file(path_, 0);
  expectLoadFails("not a positive multiple of 8");
}

TEST_F(CorruptCellFile, RandomBytes) {
  std::mt19937_64 random(12345);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<uint64_t> words(1 + random() % 512);
    for (uint64_t& word : words) word = random();
    std::ofstream(path_, std::ios::binary | std::ios::trunc)
        .write(reinterpret_cast<const char*>(words.data()), static_cast<std::streamsize>(words.size() * 8));
    const std::string error = errorOf([&] { CellGeometry::load(path_, 0, 2); });
    ASSERT_FALSE(error.empty()) << "trial " << trial;
    EXPECT_NE(error.find(path_), std::string::npos) << error;
  }
}

TEST_F(CorruptCellFile, WrongCellId) { expectLoadFails("holds cell 0, expected cell 1", 1); }

TEST_F(CorruptCellFile, MaterialBeyondTheCatalogue) { expectLoadFails("uses material 1, but the store has 1", 0, 1); }

TEST_F(CorruptCellFile, IndexOutOfRange) {
  capnp::MallocMessageBuilder message;
  auto file = message.initRoot<proto::CellFile>();
  file.setFormatVersion(proto::CELL_FORMAT_VERSION);
  file.setCellId(0);
  for (auto bounds : {file.initBoundsMin(3), file.initBoundsMax(3)})
    for (uint32_t i = 0; i < 3; ++i) bounds.set(i, float(i));
  file.setVertexCount(3);
  file.setTriangleCount(1);
  auto positions = file.initPositionChunks(1).init(0, 9);
  for (uint32_t i = 0; i < 9; ++i) positions.set(i, 0.5f * float(i % 3));
  auto indices = file.initIndexChunks(1).init(0, 3);
  indices.set(0, 0);
  indices.set(1, 7);
  indices.set(2, 2);
  file.initMaterialChunks(1).init(0, 1).set(0, 0);
  writeMessage(message);
  expectLoadFails("triangle 0 uses vertex 7, but the cell has 3 vertices");
}

TEST_F(CorruptCellFile, UnknownFormatVersion) {
  capnp::MallocMessageBuilder message;
  message.initRoot<proto::CellFile>().setFormatVersion(proto::CELL_FORMAT_VERSION + 1);
  writeMessage(message);
  expectLoadFails("cell format version");
}

TEST_F(CorruptCellFile, Missing) {
  fs::remove(path_);
  expectLoadFails("cannot open");
}

}  // namespace
}  // namespace portico
