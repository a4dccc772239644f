// The validation pass of `portico scene info` (common/scene/store/scene_validation.h)
// and the floor count beside it: generated and imported stores pass; a
// portal moved off its cells' boundaries, a truncated or missing cell file,
// a cell file disagreeing with the catalogue each give a problem naming it.
#include "common/scene/store/scene_validation.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "common/scene/import/building_importer.h"
#include "common/scene/generator/demo_generator.h"
#include "common/scene/store/floor_levels.h"
#include "common/scene/store/portal_geometry.h"
#include "common/scene/store/scene_store.h"
#include "common/util/sqlite.h"
#include "tests/unit/scene/scene_test_support.h"

namespace portico {
namespace {

namespace fs = std::filesystem;
using testing_support::TempDirectory;

const fs::path kTwoRooms = fs::path(PORTICO_REFERENCE_DIR) / "two_rooms" / "scene.json";

std::string joined(const std::vector<std::string>& problems) {
  std::string text;
  for (const std::string& problem : problems) text += problem + "\n";
  return text;
}

// Whether one problem contains every one of `parts`.
bool hasProblem(const std::vector<std::string>& problems, const std::vector<std::string>& parts) {
  return std::any_of(problems.begin(), problems.end(), [&](const std::string& problem) {
    return std::all_of(parts.begin(), parts.end(),
                       [&](const std::string& part) { return problem.find(part) != std::string::npos; });
  });
}

// Rewrites portal `id`'s polygon in the catalogue (not in the cell files).
void setPortalPolygon(const std::string& store, uint32_t id, const std::vector<Vec3>& polygon) {
  sql::Database db(store + "/scene.db", sql::Database::Mode::ReadWriteCreate);
  db.prepare("UPDATE portals SET polygon = ? WHERE id = ?")
      .bindBlob(1, polygon.data(), polygon.size() * sizeof(Vec3))
      .bind(2, int64_t{id})
      .run();
}

TEST(SceneValidation, TheDemoBuildingIsValid) {
  TempDirectory temp;
  generateDemoBuilding(temp / "demo", 3);
  const std::vector<std::string> problems = validateSceneStore(SceneStore::open(temp / "demo"));
  EXPECT_TRUE(problems.empty()) << joined(problems);
}

// The quick check (sizes only) finds a cell file cut short or gone, without
// reading any; one whose bytes changed at the same size needs the full read.
TEST(SceneValidation, TheSizeCheckFindsACellFileCutShortOrGone) {
  TempDirectory temp;
  generateDemoBuilding(temp / "demo", 3);
  const SceneStore store = SceneStore::open(temp / "demo");
  EXPECT_TRUE(validateSceneStore(store, CellFileCheck::Size).empty());
  fs::resize_file(store.cellPath(1), store.cells()[1].byteCount - 16);
  fs::remove(store.cellPath(2));
  const std::vector<std::string> problems = validateSceneStore(store, CellFileCheck::Size);
  EXPECT_TRUE(hasProblem(problems, {store.cellPath(1), "the catalogue says"})) << joined(problems);
  EXPECT_TRUE(hasProblem(problems, {store.cellPath(2), "cannot be read"})) << joined(problems);
  EXPECT_EQ(problems.size(), 2u) << joined(problems);
}

TEST(SceneValidation, ImportedCellsAndVoxelCellsAreValid) {
  if (!fs::exists(kTwoRooms)) GTEST_SKIP() << kTwoRooms << " is absent";
  TempDirectory temp;
  importBuilding({kTwoRooms.string()}, temp / "given");
  importBuilding({kTwoRooms.string()}, temp / "grid", ImportOptions{3, ""});
  for (const char* name : {"given", "grid"}) {
    const std::vector<std::string> problems = validateSceneStore(SceneStore::open(temp / name));
    EXPECT_TRUE(problems.empty()) << name << ":\n" << joined(problems);
  }
}

TEST(SceneValidation, APortalOffItsCellsBoundariesIsNamed) {
  TempDirectory temp;
  generateDemoBuilding(temp / "demo", 3);
  std::vector<Vec3> door = SceneStore::open(temp / "demo").portals()[0].polygon;   // corridor - room-1
  for (Vec3& p : door) p.z += 0.3f;
  setPortalPolygon(temp / "demo", 0, door);
  const std::vector<std::string> problems = validateSceneStore(SceneStore::open(temp / "demo"));
  EXPECT_TRUE(hasProblem(problems, {"portal 0", "not on the boundary of cell 0 ('corridor')"})) << joined(problems);
  EXPECT_TRUE(hasProblem(problems, {"portal 0", "not on the boundary of cell 1 ('room-1')"})) << joined(problems);
  // The cell files still hold the old polygon: the disagreement is reported too.
  EXPECT_TRUE(hasProblem(problems, {"cells/0.cell", "polygon of portal 0 differs"})) << joined(problems);
  for (const std::string& problem : problems) EXPECT_EQ(problem.find('\n'), std::string::npos) << problem;
}

TEST(SceneValidation, ATruncatedCellFileIsNamed) {
  TempDirectory temp;
  generateDemoBuilding(temp / "demo", 3);
  const fs::path file = fs::path(temp / "demo") / "cells" / "2.cell";
  fs::resize_file(file, fs::file_size(file) / 16 * 8);   // half, still whole words
  const std::vector<std::string> problems = validateSceneStore(SceneStore::open(temp / "demo"));
  ASSERT_EQ(problems.size(), 1u) << joined(problems);
  EXPECT_NE(problems[0].find(file.string()), std::string::npos) << problems[0];
}

TEST(SceneValidation, AMissingCellFileIsNamed) {
  TempDirectory temp;
  generateDemoBuilding(temp / "demo", 3);
  const fs::path file = fs::path(temp / "demo") / "cells" / "4.cell";
  fs::remove(file);
  const std::vector<std::string> problems = validateSceneStore(SceneStore::open(temp / "demo"));
  EXPECT_TRUE(hasProblem(problems, {file.string(), "cannot open"})) << joined(problems);
}

TEST(SceneValidation, ACellFileOfAnotherCellIsNamed) {
  TempDirectory temp;
  generateDemoBuilding(temp / "demo", 3);
  const fs::path cells = fs::path(temp / "demo") / "cells";
  fs::copy_file(cells / "1.cell", cells / "3.cell", fs::copy_options::overwrite_existing);
  const std::vector<std::string> problems = validateSceneStore(SceneStore::open(temp / "demo"));
  EXPECT_TRUE(hasProblem(problems, {(cells / "3.cell").string(), "holds cell 1, expected cell 3"})) << joined(problems);
}

TEST(SceneValidation, ALightOutsideItsCellIsNamed) {
  TempDirectory temp;
  generateDemoBuilding(temp / "demo", 3);
  {
    sql::Database db(temp / "demo/scene.db", sql::Database::Mode::ReadWriteCreate);
    db.exec("UPDATE lights SET corner_y = corner_y + 100 WHERE id = 0");
  }
  const std::vector<std::string> problems = validateSceneStore(SceneStore::open(temp / "demo"));
  EXPECT_TRUE(hasProblem(problems, {"light 0", "outside the bounds"})) << joined(problems);
}

// Every named camera is checked, each problem naming the camera; a camera
// in a cell that does not exist is refused when the store is opened.
TEST(SceneValidation, ACameraOutsideItsCellIsNamed) {
  TempDirectory temp;
  generateDemoBuilding(temp / "demo", 3);
  {
    sql::Database db(temp / "demo/scene.db", sql::Database::Mode::ReadWriteCreate);
    db.exec("UPDATE cameras SET origin_y = origin_y + 100 WHERE name IN ('corridor', 'room-2')");
  }
  const std::vector<std::string> problems = validateSceneStore(SceneStore::open(temp / "demo"));
  EXPECT_EQ(problems.size(), 2u) << joined(problems);
  EXPECT_TRUE(hasProblem(problems, {"camera 'corridor': origin", "outside the bounds of its cell 0 ('corridor')"}))
      << joined(problems);
  EXPECT_TRUE(hasProblem(problems, {"camera 'room-2': origin", "cell 2 ('room-2')"})) << joined(problems);
  {
    sql::Database db(temp / "demo/scene.db", sql::Database::Mode::ReadWriteCreate);
    db.exec("UPDATE cameras SET cell = 99 WHERE name = 'dark-room'");
  }
  try {
    SceneStore::open(temp / "demo");
    ADD_FAILURE() << "a camera in cell 99 of 8 was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("camera 'dark-room' refers to cell 99"), std::string::npos) << e.what();
  }
}

TEST(PortalGeometry, OnABoxFaceOrNot) {
  const Bounds3 box(Vec3(0, 0, 0), Vec3(4, 3, 2));
  EXPECT_EQ(portalBoundaryProblem(box, {Vec3(4, 0, 0.5f), Vec3(4, 0, 1.5f), Vec3(4, 2, 1.5f)}), "");
  EXPECT_EQ(portalBoundaryProblem(box, {Vec3(0, 3, 0), Vec3(4, 3, 0), Vec3(4, 3, 2), Vec3(0, 3, 2)}), "");
  // A few ulps off the face is still on it.
  EXPECT_EQ(portalBoundaryProblem(box, {Vec3(4.00001f, 0, 0.5f), Vec3(4, 0, 1.5f), Vec3(3.99999f, 2, 1.5f)}), "");
  EXPECT_NE(portalBoundaryProblem(box, {Vec3(2, 0, 0.5f), Vec3(2, 0, 1.5f), Vec3(2, 2, 1.5f)})
                .find("not on one of its faces"),
            std::string::npos);
  EXPECT_NE(portalBoundaryProblem(box, {Vec3(5, 0, 0.5f), Vec3(5, 0, 1.5f), Vec3(5, 2, 1.5f)}).find("point 0"),
            std::string::npos);
  // Each point on some face, but not all on the same one.
  EXPECT_NE(portalBoundaryProblem(box, {Vec3(0, 0, 0), Vec3(4, 0, 2), Vec3(4, 3, 2)}), "");
}

CellInfo cellAt(uint32_t id, float bottom, uint64_t triangles, float size = 4.0f) {
  CellInfo cell;
  cell.id = id;
  cell.bounds = Bounds3(Vec3(0, bottom, 0), Vec3(size, bottom + 2.8f, size));
  cell.triangleCount = triangles;
  return cell;
}

TEST(FloorLevels, BottomsWithinHalfAMetreAreOneFloor) {
  const std::vector<CellInfo> cells{cellAt(0, 0.0f, 10),  cellAt(1, 0.3f, 10),  cellAt(2, 3.0f, 10),
                                    cellAt(3, 3.45f, 10), cellAt(4, 6.0f, 10),  cellAt(5, 2.9f, 0, 100.0f),
                                    cellAt(6, -0.001f, 0)};
  const FloorLevels floors = findFloorLevels(cells);
  EXPECT_EQ(floors.levels, (std::vector<float>{0.0f, 3.0f, 6.0f}));
  EXPECT_EQ(floors.cellFloor, (std::vector<uint32_t>{0, 0, 1, 1, 2, 0, 0}));
}

TEST(FloorLevels, AStaircaseDoesNotChainIntoOneFloor) {
  std::vector<CellInfo> cells;
  for (uint32_t i = 0; i < 8; ++i) cells.push_back(cellAt(i, 0.3f * float(i), 1));
  // Bottoms 0, 0.3, ..., 2.1: floors start at 0, 0.6, 1.2, 1.8.
  EXPECT_EQ(findFloorLevels(cells).levels.size(), 4u);
}

TEST(FloorLevels, TheStoreMetaWins) {
  TempDirectory temp;
  generateDemoBuilding(temp / "demo", 3);
  EXPECT_EQ(floorCount(SceneStore::open(temp / "demo")), 1u);
  {
    sql::Database db(temp / "demo/scene.db", sql::Database::Mode::ReadWriteCreate);
    db.exec("INSERT INTO meta VALUES ('floors', '7')");
  }
  EXPECT_EQ(floorCount(SceneStore::open(temp / "demo")), 7u);
}

// A door given twice, or a thousand times, in a catalogue written by hand:
// every ray of its cells would test each copy. Named once, then counted.
TEST(SceneValidation, DuplicatePortalsAreNamed) {
  TempDirectory temp;
  generateDemoBuilding(temp / "demo", 3);
  {
    sql::Database db(temp / "demo" + "/scene.db", sql::Database::Mode::ReadWriteCreate);
    db.exec("BEGIN");   // one commit, not a thousand
    for (int copy = 0; copy < 1000; ++copy)
      db.exec("INSERT INTO portals(cell_a, cell_b, polygon) SELECT cell_a, cell_b, polygon FROM portals WHERE id = 0");
    db.exec("COMMIT");
  }
  const std::vector<std::string> problems = validateSceneStore(SceneStore::open(temp / "demo"));
  EXPECT_TRUE(hasProblem(problems, {"duplicates portal"})) << joined(problems);
  EXPECT_TRUE(hasProblem(problems, {"999 more duplicate portals"})) << joined(problems);
}

}  // namespace
}  // namespace portico
