// The demo building: deterministic, and a well-formed cells-and-portals
// scene (portals on cell boundaries, walls closed around doors, ceilings and
// lights hidden from the camera for the cut-away view, lights where the
// description says).
#include "common/scene/generator/demo_generator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/scene/store/cell_geometry.h"
#include "common/scene/store/scene_store.h"
#include "tests/unit/scene/scene_test_support.h"
#include "tests/unit/scene/standing_camera_checks.h"

namespace portico {
namespace {

namespace fs = std::filesystem;
using testing_support::readBytes;
using testing_support::TempDirectory;

constexpr float kTolerance = 1e-4f;

class DemoBuilding : public ::testing::Test {
 protected:
  void SetUp() override {
    generateDemoBuilding(temp_ / "demo", 7);
    store_ = std::make_unique<SceneStore>(SceneStore::open(temp_ / "demo"));
    for (const CellInfo& cell : store_->cells())
      geometry_.push_back(CellGeometry::load(store_->cellPath(cell.id), cell.id, store_->materials().size()));
  }
  const SceneStore& store() const { return *store_; }
  const CellGeometry& geometry(uint32_t cell) const { return *geometry_[cell]; }
  std::vector<const AreaLight*> lightsIn(uint32_t cell) const {
    std::vector<const AreaLight*> lights;
    for (const AreaLight& light : store().lights())
      if (light.cell == cell) lights.push_back(&light);
    return lights;
  }
  const Portal* portalBetween(uint32_t a, uint32_t b) const {
    for (const Portal& portal : store().portals())
      if ((portal.cellA == a && portal.cellB == b) || (portal.cellA == b && portal.cellB == a)) return &portal;
    return nullptr;
  }
  const Material& materialOf(uint32_t cell, uint32_t triangle) const {
    return store().materials()[geometry(cell).material(triangle)];
  }
  // The height of the cell's ceiling: the plane of its "ceiling" triangles
  // (nullopt if it has none, or if they do not share one plane y = c).
  std::optional<float> ceilingHeight(uint32_t cell) const {
    const MeshView& mesh = geometry(cell).mesh();
    std::optional<float> height;
    for (uint32_t t = 0; t < mesh.triangleCount; ++t) {
      if (materialOf(cell, t).name != "ceiling") continue;
      Vec3 a, b, c;
      mesh.triangle(t, a, b, c);
      for (const Vec3& v : {a, b, c}) {
        if (height && std::abs(v.y - *height) > kTolerance) return std::nullopt;
        height = v.y;
      }
    }
    return height;
  }

  TempDirectory temp_;
  std::unique_ptr<SceneStore> store_;
  std::vector<std::unique_ptr<CellGeometry>> geometry_;
};

Vec3 centroid(const std::vector<Vec3>& polygon) {
  Vec3 sum(0);
  for (const Vec3& v : polygon) sum += v;
  return sum / float(polygon.size());
}

float polygonArea(const std::vector<Vec3>& polygon) {
  Vec3 sum(0);
  for (size_t i = 1; i + 1 < polygon.size(); ++i) sum += cross(polygon[i] - polygon[0], polygon[i + 1] - polygon[0]);
  return 0.5f * length(sum);
}

bool nearlyInside(const Bounds3& box, const Vec3& p, float tolerance) {
  return Bounds3(box.lo - Vec3(tolerance), box.hi + Vec3(tolerance)).contains(p);
}

TEST(DemoBuildingGenerator, SameSeedWritesTheSameBytes) {
  TempDirectory temp;
  generateDemoBuilding(temp / "a", 7);
  generateDemoBuilding(temp / "b", 7);
  generateDemoBuilding(temp / "c", 8);
  const SceneStore a = SceneStore::open(temp / "a");
  bool seedsDiffer = false;
  for (const CellInfo& cell : a.cells()) {
    const auto bytesA = readBytes(fs::path(temp / "a") / cell.file);
    EXPECT_EQ(bytesA, readBytes(fs::path(temp / "b") / cell.file)) << cell.file;
    seedsDiffer |= bytesA != readBytes(fs::path(temp / "c") / cell.file);
  }
  EXPECT_EQ(readBytes(fs::path(temp / "a") / "scene.db"), readBytes(fs::path(temp / "b") / "scene.db"));
  EXPECT_TRUE(seedsDiffer) << "the seed changes nothing";
  EXPECT_EQ(SceneStore::open(temp / "c").meta().at("seed"), "8");
}

TEST_F(DemoBuilding, HasSixRoomsACorridorAndAnEmptySky) {
  ASSERT_EQ(store().cells().size(), kDemoCellCount);
  EXPECT_EQ(store().cells()[kDemoCorridorCell].name, "corridor");
  EXPECT_EQ(store().cells()[kDemoDarkRoomCell].name, "dark-room");
  EXPECT_EQ(store().cells()[kDemoSkyCell].name, "sky");
  EXPECT_EQ(kDemoSkyCell, store().cells().size() - 1);
  int rooms = 0;
  for (const CellInfo& cell : store().cells()) {
    if (cell.id == kDemoCorridorCell || cell.id == kDemoSkyCell) continue;
    ++rooms;
    EXPECT_NE(portalBetween(cell.id, kDemoCorridorCell), nullptr) << cell.name << " has no door";
    EXPECT_NE(portalBetween(cell.id, kDemoSkyCell), nullptr) << cell.name << " is not open to the sky";
    EXPECT_GT(cell.triangleCount, 10u) << cell.name << " is unfurnished";
  }
  EXPECT_GE(rooms, 6);
  EXPECT_EQ(store().cells()[kDemoSkyCell].triangleCount, 0u);
  EXPECT_EQ(geometry(kDemoSkyCell).mesh().triangleCount, 0u);
  EXPECT_EQ(store().camera().cell, kDemoSkyCell);
  EXPECT_EQ(store().locateCell(store().camera().origin), kDemoSkyCell);
  EXPECT_EQ(store().camera().width, 480u);
  EXPECT_EQ(store().camera().height, 320u);
  EXPECT_EQ(store().meta().at("generator"), "demo");
  EXPECT_EQ(store().meta().at("seed"), "7");
}

TEST_F(DemoBuilding, EveryRoomButTheDarkOneHasADownwardLight) {
  for (const CellInfo& cell : store().cells()) {
    const auto lights = lightsIn(cell.id);
    if (cell.id == kDemoDarkRoomCell || cell.id == kDemoSkyCell)
      EXPECT_TRUE(lights.empty()) << cell.name;
    else if (cell.id == kDemoCorridorCell)
      EXPECT_TRUE(lights.size() == 1 || lights.size() == 2) << lights.size();
    else
      EXPECT_EQ(lights.size(), 1u) << cell.name;

    // The lights' triangles are in the cell, emissive and facing down, and
    // nothing else in the cell is emissive.
    const MeshView& mesh = geometry(cell.id).mesh();
    size_t emissiveTriangles = 0;
    for (uint32_t t = 0; t < mesh.triangleCount; ++t) {
      if (!store().materials()[geometry(cell.id).material(t)].emissive()) continue;
      ++emissiveTriangles;
      const Vec3 normal = normalize(mesh.geometricNormal(t));
      EXPECT_NEAR(normal.y, -1.0f, 1e-6f) << cell.name << " triangle " << t;
      Vec3 a, b, c;
      mesh.triangle(t, a, b, c);
      bool onALight = false;
      for (const AreaLight* light : lights)
        onALight |= std::abs(a.y - light->corner.y) < kTolerance &&
                    nearlyInside(Bounds3(light->corner, light->corner + light->edge1 + light->edge2),
                                 centroid({a, b, c}), kTolerance);
      EXPECT_TRUE(onALight) << cell.name << ": emissive triangle " << t << " belongs to no light";
    }
    EXPECT_EQ(emissiveTriangles, 2 * lights.size()) << cell.name;
  }
  // Flush ceiling panels: within 2 mm below their cell's ceiling, inside the cell.
  for (const AreaLight& light : store().lights()) {
    EXPECT_NEAR(light.normal().y, -1.0f, 1e-6f);
    EXPECT_GE(light.area(), 0.6f * 0.6f - kTolerance);
    EXPECT_LE(light.area(), 1.0f + kTolerance);
    const std::optional<float> ceiling = ceilingHeight(light.cell);
    ASSERT_TRUE(ceiling.has_value()) << "light " << light.id << ": its cell has no flat ceiling";
    EXPECT_LT(light.center().y, *ceiling) << "light " << light.id;
    EXPECT_GE(light.center().y, *ceiling - 0.002f) << "light " << light.id;
    const Bounds3& box = store().cells()[light.cell].bounds;
    for (const Vec3& corner : {light.corner, light.corner + light.edge1, light.corner + light.edge2,
                               light.corner + light.edge1 + light.edge2})
      EXPECT_TRUE(box.contains(corner)) << "light " << light.id << " sticks out of cell " << light.cell;
  }
}

// The cut-away view: the camera looks through ceilings and lamps (materials
// hidden from it) and sees everything else.
TEST_F(DemoBuilding, OnlyCeilingsAndLightsAreHiddenFromTheCamera) {
  bool hasCeiling = false;
  for (const Material& material : store().materials()) {
    const bool shouldHide = material.name == "ceiling" || material.name == "light";
    EXPECT_EQ(material.hiddenFromCamera, shouldHide) << material.name;
    if (material.emissive()) EXPECT_TRUE(material.hiddenFromCamera) << material.name;
    if (material.name == "ceiling") {
      hasCeiling = true;
      EXPECT_FALSE(material.emissive());
      EXPECT_GE(maxComponent(material.albedo), 0.7f);
    }
  }
  EXPECT_TRUE(hasCeiling);
  // Hidden triangles are ceilings or lamps, all facing down.
  for (const CellInfo& cell : store().cells()) {
    const MeshView& mesh = geometry(cell.id).mesh();
    for (uint32_t t = 0; t < mesh.triangleCount; ++t)
      if (materialOf(cell.id, t).hiddenFromCamera)
        EXPECT_NEAR(normalize(mesh.geometricNormal(t)).y, -1.0f, 1e-6f) << cell.name << " triangle " << t;
  }
}

TEST_F(DemoBuilding, DarkRoomDoorFacesACorridorLight) {
  const Portal* door = portalBetween(kDemoDarkRoomCell, kDemoCorridorCell);
  ASSERT_NE(door, nullptr);
  const Vec3 doorCenter = centroid(door->polygon);
  bool facing = false;
  for (const AreaLight* light : lightsIn(kDemoCorridorCell))
    facing |= std::abs(light->center().x - doorCenter.x) < 0.5f;
  EXPECT_TRUE(facing) << "no corridor light in front of the dark room's door at x = " << doorCenter.x;
  EXPECT_NEAR(polygonArea(door->polygon), 0.9f * 2.1f, kTolerance);
}

TEST_F(DemoBuilding, PortalsLieOnTheBoundaryOfBothTheirCells) {
  for (const Portal& portal : store().portals()) {
    ASSERT_EQ(portal.polygon.size(), 4u) << "portal " << portal.id;
    for (uint32_t cell : {portal.cellA, portal.cellB}) {
      const Bounds3& box = store().cells()[cell].bounds;
      bool onAFace = false;
      for (int axis = 0; axis < 3; ++axis)
        for (float plane : {box.lo[axis], box.hi[axis]}) {
          bool all = true;
          for (const Vec3& v : portal.polygon) all &= std::abs(v[axis] - plane) <= kTolerance;
          onAFace |= all;
        }
      EXPECT_TRUE(onAFace) << "portal " << portal.id << " is not on a face of cell " << cell;
      for (const Vec3& v : portal.polygon)
        EXPECT_TRUE(nearlyInside(box, v, kTolerance)) << "portal " << portal.id << " leaves cell " << cell;
    }
  }
}

TEST_F(DemoBuilding, TrianglesLieWithinTheirCell) {
  for (const CellInfo& cell : store().cells()) {
    const MeshView& mesh = geometry(cell.id).mesh();
    for (uint32_t v = 0; v < mesh.vertexCount; ++v)
      ASSERT_TRUE(nearlyInside(cell.bounds, mesh.vertex(v), kTolerance)) << cell.name << " vertex " << v;
    for (uint32_t t = 0; t < mesh.triangleCount; ++t)
      ASSERT_GT(length(mesh.geometricNormal(t)), 1e-6f) << cell.name << " triangle " << t << " is degenerate";
  }
}

TEST_F(DemoBuilding, CellFilesListTheCataloguePortals) {
  for (const CellInfo& cell : store().cells()) {
    std::vector<const Portal*> expected;
    for (const Portal& portal : store().portals())
      if (portal.cellA == cell.id || portal.cellB == cell.id) expected.push_back(&portal);
    const auto& views = geometry(cell.id).portals();
    ASSERT_EQ(views.size(), expected.size()) << cell.name;
    for (size_t i = 0; i < views.size(); ++i) {
      EXPECT_EQ(views[i].portalId, expected[i]->id);
      EXPECT_EQ(views[i].neighborCell, expected[i]->cellA == cell.id ? expected[i]->cellB : expected[i]->cellA);
      EXPECT_EQ(views[i].polygon, expected[i]->polygon);
    }
  }
}

// The area of the part of a planar polygon with y <= yMax.
double areaBelow(const std::vector<Vec3>& polygon, float yMax) {
  std::vector<Vec3> clipped;
  for (size_t i = 0; i < polygon.size(); ++i) {
    const Vec3& a = polygon[i];
    const Vec3& b = polygon[(i + 1) % polygon.size()];
    if (a.y <= yMax) clipped.push_back(a);
    if ((a.y < yMax) != (b.y < yMax) && a.y != b.y && a.y != yMax && b.y != yMax)
      clipped.push_back(a + (b - a) * ((yMax - a.y) / (b.y - a.y)));
  }
  return clipped.size() < 3 ? 0.0 : polygonArea(clipped);
}

// A room or the corridor as a closed box: every face of `box` is covered
// exactly once, by inward-facing triangles or by the cell's portals, each
// counted only below yMax (for the box under the ceiling). A gap would let
// rays leak out of the cell; an overlap would double a wall.
void expectClosedBox(const SceneStore& store, const CellGeometry& geometry, const std::string& name, uint32_t cellId,
                     const Bounds3& box, const std::string& what) {
  const MeshView& mesh = geometry.mesh();
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const float plane = side ? box.hi[axis] : box.lo[axis];
      const Vec3 inward = [&] { Vec3 n(0); n[axis] = side ? -1.0f : 1.0f; return n; }();
      const auto onPlane = [&](const Vec3& v) { return std::abs(v[axis] - plane) <= kTolerance; };
      double covered = 0;
      for (uint32_t t = 0; t < mesh.triangleCount; ++t) {
        Vec3 a, b, c;
        mesh.triangle(t, a, b, c);
        if (!onPlane(a) || !onPlane(b) || !onPlane(c)) continue;
        const double area = areaBelow({a, b, c}, box.hi.y);
        if (area == 0) continue;
        EXPECT_GT(dot(mesh.geometricNormal(t), inward), 0.0f)
            << name << " " << what << ": triangle " << t << " faces out of the box";
        covered += area;
      }
      for (const Portal& portal : store.portals()) {
        if (portal.cellA != cellId && portal.cellB != cellId) continue;
        bool all = true;
        for (const Vec3& v : portal.polygon) all &= onPlane(v);
        if (all) covered += areaBelow(portal.polygon, box.hi.y);
      }
      const Vec3 d = box.diagonal();
      const double faceArea = double(d[(axis + 1) % 3]) * double(d[(axis + 2) % 3]);
      EXPECT_NEAR(covered, faceArea, 1e-3) << name << " " << what << ": face axis " << axis << " side " << side;
    }
}

// Cut-away: each room and the corridor is closed under its ceiling (walls,
// floor, ceiling, doors), and its cell box, which reaches above the ceiling,
// is closed too, its top face being exactly the portal to the sky. Photons
// going up hit the ceiling well before the portal; camera rays from the sky
// come in through the portal and pass the hidden ceiling.
TEST_F(DemoBuilding, WallsCloseEachCellExceptThroughItsPortals) {
  for (const CellInfo& cell : store().cells()) {
    if (cell.id == kDemoSkyCell) continue;
    const Bounds3& box = cell.bounds;
    const std::optional<float> ceiling = ceilingHeight(cell.id);
    ASSERT_TRUE(ceiling.has_value()) << cell.name << " has no flat ceiling";
    EXPECT_GE(box.hi.y - *ceiling, 0.05f) << cell.name << ": the ceiling is too close to the sky portal";
    EXPECT_GT(*ceiling, 2.0f) << cell.name;

    // The room under its ceiling.
    Bounds3 room = box;
    room.hi.y = *ceiling;
    expectClosedBox(store(), geometry(cell.id), cell.name, cell.id, room, "under the ceiling");
    // The whole cell box.
    expectClosedBox(store(), geometry(cell.id), cell.name, cell.id, box, "cell box");

    // The ceiling plane holds only downward ceiling triangles and lamps.
    const MeshView& mesh = geometry(cell.id).mesh();
    for (uint32_t t = 0; t < mesh.triangleCount; ++t) {
      Vec3 a, b, c;
      mesh.triangle(t, a, b, c);
      const bool onCeiling = std::abs(a.y - *ceiling) <= kTolerance && std::abs(b.y - *ceiling) <= kTolerance &&
                             std::abs(c.y - *ceiling) <= kTolerance;
      if (onCeiling) EXPECT_EQ(materialOf(cell.id, t).name, "ceiling") << cell.name << " triangle " << t;
      // Nothing but walls reaches above the ceiling.
      if (std::max({a.y, b.y, c.y}) > *ceiling + kTolerance)
        EXPECT_TRUE(std::abs(a.y - b.y) > kTolerance || std::abs(a.y - c.y) > kTolerance)
            << cell.name << " triangle " << t << " is a horizontal surface above the ceiling";
    }

    // The top face of the cell box: exactly one portal, to the sky, and no triangle.
    const Portal* top = portalBetween(cell.id, kDemoSkyCell);
    ASSERT_NE(top, nullptr) << cell.name;
    for (const Vec3& v : top->polygon) EXPECT_NEAR(v.y, box.hi.y, kTolerance) << cell.name;
    EXPECT_NEAR(polygonArea(top->polygon), (box.hi.x - box.lo.x) * (box.hi.z - box.lo.z), 1e-3) << cell.name;
    EXPECT_NEAR(store().cells()[kDemoSkyCell].bounds.lo.y, box.hi.y, kTolerance) << cell.name;
  }
}

TEST_F(DemoBuilding, CameraSeesTheWholeFloor) {
  const Camera& camera = store().camera();
  const Vec3 forward = normalize(camera.target - camera.origin);
  const Vec3 right = normalize(cross(forward, camera.up));
  const Vec3 up = cross(right, forward);
  const float tanHalf = std::tan(0.5f * camera.fovYDegrees * kPi / 180.0f);
  const float aspect = float(camera.width) / float(camera.height);
  const Vec3 down = normalize(camera.target - camera.origin);
  EXPECT_GT(std::asin(-down.y) * 180.0f / kPi, 50.0f);
  EXPECT_LT(std::asin(-down.y) * 180.0f / kPi, 60.0f);
  for (const CellInfo& cell : store().cells()) {
    if (cell.id == kDemoSkyCell) continue;
    for (int corner = 0; corner < 8; ++corner) {
      const Vec3 p((corner & 1) ? cell.bounds.hi.x : cell.bounds.lo.x, (corner & 2) ? cell.bounds.hi.y : cell.bounds.lo.y,
                   (corner & 4) ? cell.bounds.hi.z : cell.bounds.lo.z);
      const Vec3 d = p - camera.origin;
      const float depth = dot(d, forward);
      ASSERT_GT(depth, 0.0f);
      EXPECT_LE(std::abs(dot(d, right) / depth / (tanHalf * aspect)), 1.0f) << cell.name << " corner " << corner;
      EXPECT_LE(std::abs(dot(d, up) / depth / tanHalf), 1.0f) << cell.name << " corner " << corner;
    }
  }
}

// "overview" (the default) and a standing camera in every room, named as
// the room, and in the corridor.
TEST_F(DemoBuilding, EveryRoomAndTheCorridorHasANamedCamera) {
  EXPECT_EQ(store().camera().name, "overview");
  EXPECT_EQ(store().camera().cell, kDemoSkyCell);
  EXPECT_EQ(store().cameras().size(), kDemoCellCount);   // the overview and one per cell but the sky
  for (const CellInfo& cell : store().cells()) {
    if (cell.id == kDemoSkyCell) continue;
    const Camera* camera = store().findCamera(cell.name);
    ASSERT_NE(camera, nullptr) << cell.name;
    EXPECT_EQ(camera->cell, cell.id);
    testing_support::expectStandingCameraInItsCell(store(), *camera);
  }
}

TEST_F(DemoBuilding, MaterialsArePlausible) {
  bool hasEmitter = false;
  for (const Material& material : store().materials()) {
    EXPECT_LE(maxComponent(material.albedo), 0.85f) << material.name;
    if (material.emissive()) {
      hasEmitter = true;
      EXPECT_EQ(maxComponent(material.albedo), 0.0f) << material.name;
    }
  }
  EXPECT_TRUE(hasEmitter);
}

}  // namespace
}  // namespace portico
