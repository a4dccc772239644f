// The demo building (see demo_generator.h): plans the rooms, adds portals,
// lights and materials, then writes one cell at a time.
#include "common/scene/generator/demo_generator.h"

#include <algorithm>
#include <array>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/scene/generator/demo_furniture.h"
#include "common/scene/generator/material_palette.h"
#include "common/scene/generator/mesh_builder.h"
#include "common/scene/generator/standing_camera.h"
#include "common/scene/store/scene_store.h"

namespace portico {

namespace {

using demo::DemoMaterials;
using demo::DemoRandom;
using demo::RoomFrame;

constexpr float kWallHeight = 2.8f;   // the ceiling's height
// Cut-away: each room's cell box reaches kCutawayGap above its ceiling, and
// its top face there is the portal to the sky. Photons going up hit the
// ceiling well before the portal; camera rays come in through the portal and
// pass the ceiling (a material hidden from the camera, seen from above)
// into the room.
constexpr float kCutawayGap = 0.1f;
constexpr float kCellTop = kWallHeight + kCutawayGap;
constexpr float kDoorWidth = 0.9f;
constexpr float kDoorHeight = 2.1f;
constexpr float kCorridorLength = 14.0f;
constexpr float kCorridorHalfWidth = 1.0f;
constexpr float kRoomDepth = 4.0f;
constexpr float kLightY = kWallHeight - 0.001f;   // a flush panel 1 mm under the ceiling
constexpr float kCorridorLightSize = 0.8f;
constexpr float kSkyHeight = 50.0f;
constexpr float kSkyMargin = 2.0f;
constexpr float kDoorClearance = 1.3f;   // furniture-free strip inside each door

// The fixed floor plan; the seed varies everything inside it.
struct RoomPlan {
  const char* name;
  float x0, x1;
  bool north;   // north rooms lie at z > 0
  bool lit;
};
constexpr std::array<RoomPlan, 6> kRoomPlans{{
    {"room-1", 0.0f, 4.5f, true, true},
    {"room-2", 4.5f, 9.5f, true, true},
    {"room-3", 9.5f, 14.0f, true, true},
    {"room-4", 0.0f, 5.0f, false, true},
    {"dark-room", 5.0f, 9.0f, false, false},
    {"room-5", 9.0f, 14.0f, false, true},
}};
// The dark room's door is centred in it and a corridor light hangs right in
// front of it; the second corridor light is for the west end.
constexpr float kDarkDoorCenter = 7.0f;
constexpr std::array<float, 2> kCorridorLightX{kDarkDoorCenter, 2.5f};

// A room once the seed has decided its details.
struct Room {
  uint32_t cell = 0;
  RoomPlan plan{};
  Bounds3 bounds;
  float corridorWallZ = 0;   // plane of the wall shared with the corridor
  float farWallZ = 0;
  float doorX0 = 0, doorX1 = 0;
  uint32_t backWallMaterial = 0;
  float lightSize = 0;        // 0 for the dark room
};

// The furniture's materials plus the generator's own.
struct Materials : DemoMaterials {
  uint32_t ceiling = 0;   // hidden from the camera, like the lights
};

Materials addMaterials(SceneStoreWriter& writer) {
  Materials m{};
  m.roomFloor = palette::add(writer, palette::kFloorWood);
  m.corridorFloor = palette::add(writer, palette::kFloorTiles);
  m.wall = palette::add(writer, palette::kWallWhite);
  m.accentWalls[0] = palette::add(writer, palette::kWallBlue);
  m.accentWalls[1] = palette::add(writer, palette::kWallTerracotta);
  m.accentWalls[2] = palette::add(writer, palette::kWallSage);
  m.wood = palette::add(writer, palette::kWood);
  m.darkWood = palette::add(writer, palette::kDarkWood);
  m.cabinet = palette::add(writer, palette::kCabinetWhite);
  m.metal = palette::add(writer, palette::kMetalGrey);
  for (int k = 0; k < 3; ++k) m.fabrics[k] = palette::add(writer, palette::kFabrics[k]);
  for (int k = 0; k < 3; ++k) m.books[k] = palette::add(writer, palette::kBooks[k]);
  m.light = palette::add(writer, palette::kLight);
  m.ceiling = palette::add(writer, palette::kCeiling);
  return m;
}

std::vector<Room> planRooms(const DemoMaterials& materials, DemoRandom& random) {
  std::vector<Room> rooms;
  for (size_t i = 0; i < kRoomPlans.size(); ++i) {
    Room room;
    room.cell = static_cast<uint32_t>(1 + i);
    room.plan = kRoomPlans[i];
    const float side = room.plan.north ? 1.0f : -1.0f;
    room.corridorWallZ = side * kCorridorHalfWidth;
    room.farWallZ = side * (kCorridorHalfWidth + kRoomDepth);
    room.bounds = Bounds3(Vec3(room.plan.x0, 0.0f, std::min(room.corridorWallZ, room.farWallZ)),
                          Vec3(room.plan.x1, kCellTop, std::max(room.corridorWallZ, room.farWallZ)));
    room.doorX0 = room.plan.lit ? random.centimetres(room.plan.x0 + 0.4f, room.plan.x1 - 0.4f - kDoorWidth)
                                : kDarkDoorCenter - 0.5f * kDoorWidth;
    room.doorX1 = room.doorX0 + kDoorWidth;
    const uint32_t wallChoice = random.index(4);
    room.backWallMaterial = wallChoice == 3 ? materials.wall : materials.accentWalls[wallChoice];
    room.lightSize = room.plan.lit ? random.centimetres(0.6f, 1.0f) : 0.0f;
    rooms.push_back(room);
  }
  return rooms;
}

// A flush ceiling panel facing down (cross(edge1, edge2) = -y) centred at (x, z).
AreaLight ceilingLight(uint32_t cell, float x, float z, float size) {
  AreaLight light;
  light.cell = cell;
  light.corner = Vec3(x - 0.5f * size, kLightY, z - 0.5f * size);
  light.edge1 = Vec3(size, 0.0f, 0.0f);
  light.edge2 = Vec3(0.0f, 0.0f, size);
  return light;   // its radiance: PanelMaterials
}

// The rectangle a cell shows to the sky: the top face of its box, above the ceiling.
std::vector<Vec3> topRectangle(const Bounds3& box) {
  return {Vec3(box.lo.x, kCellTop, box.lo.z), Vec3(box.hi.x, kCellTop, box.lo.z),
          Vec3(box.hi.x, kCellTop, box.hi.z), Vec3(box.lo.x, kCellTop, box.hi.z)};
}

std::vector<Vec3> doorRectangle(const Room& room) {
  const float z = room.corridorWallZ;
  return {Vec3(room.doorX0, 0.0f, z), Vec3(room.doorX1, 0.0f, z), Vec3(room.doorX1, kDoorHeight, z),
          Vec3(room.doorX0, kDoorHeight, z)};
}

// The door opening in a z = const wall, in that wall's (u = x, v = y) plane.
PlaneRect doorHole(const Room& room) { return PlaneRect{room.doorX0, room.doorX1, 0.0f, kDoorHeight}; }

// Floor, ceiling and four walls facing into the box; walls at z = const may
// have doors. The walls run up to the top of the cell's box (kCutawayGap above
// the ceiling), so the box stays closed but for its portals; the strip above
// the ceiling is only ever seen by camera rays, as the walls' continuation.
void addShell(MeshBuilder& mesh, const Bounds3& box, uint32_t floorMaterial, uint32_t wallMaterial,
              uint32_t ceilingMaterial, const std::vector<PlaneRect>& holesAtLowZ,
              const std::vector<PlaneRect>& holesAtHighZ, uint32_t lowZMaterial, uint32_t highZMaterial) {
  const PlaneRect footprint{box.lo.z, box.hi.z, box.lo.x, box.hi.x};
  mesh.addAxisRectangle(1, 0.0f, true, footprint, floorMaterial);
  mesh.addAxisRectangle(1, kWallHeight, false, footprint, ceilingMaterial);
  const PlaneRect zWall{box.lo.x, box.hi.x, 0.0f, box.hi.y};
  mesh.addAxisRectangle(2, box.lo.z, true, zWall, lowZMaterial, holesAtLowZ);
  mesh.addAxisRectangle(2, box.hi.z, false, zWall, highZMaterial, holesAtHighZ);
  const PlaneRect xWall{0.0f, box.hi.y, box.lo.z, box.hi.z};
  mesh.addAxisRectangle(0, box.lo.x, true, xWall, wallMaterial);
  mesh.addAxisRectangle(0, box.hi.x, false, xWall, wallMaterial);
}

// The lamps of `cell` among `lights` (lightMaterials: one per light) as geometry.
void addLamps(MeshBuilder& mesh, uint32_t cell, const std::vector<AreaLight>& lights,
              const std::vector<uint32_t>& lightMaterials) {
  for (size_t k = 0; k < lights.size(); ++k)
    if (lights[k].cell == cell) mesh.addParallelogram(lights[k].corner, lights[k].edge1, lights[k].edge2, lightMaterials[k]);
}

CellContent corridorCell(const Bounds3& box, const std::vector<Room>& rooms, const std::vector<AreaLight>& lights,
                         const std::vector<uint32_t>& lightMaterials, const Materials& materials) {
  CellContent cell;
  cell.id = kDemoCorridorCell;
  cell.name = "corridor";
  cell.bounds = box;
  std::vector<PlaneRect> southDoors, northDoors;
  for (const Room& room : rooms) (room.plan.north ? northDoors : southDoors).push_back(doorHole(room));
  MeshBuilder mesh;
  addShell(mesh, cell.bounds, materials.corridorFloor, materials.wall, materials.ceiling, southDoors, northDoors,
           materials.wall, materials.wall);
  addLamps(mesh, cell.id, lights, lightMaterials);
  mesh.moveInto(cell);
  return cell;
}

CellContent roomCell(const Room& room, const std::vector<AreaLight>& lights, const std::vector<uint32_t>& lightMaterials,
                     const Materials& materials, DemoRandom& random) {
  CellContent cell;
  cell.id = room.cell;
  cell.name = room.plan.name;
  cell.bounds = room.bounds;
  const std::vector<PlaneRect> door{doorHole(room)};
  MeshBuilder mesh;
  // The corridor wall is at low z for north rooms, at high z for south ones.
  if (room.plan.north)
    addShell(mesh, cell.bounds, materials.roomFloor, materials.wall, materials.ceiling, door, {}, materials.wall,
             room.backWallMaterial);
  else
    addShell(mesh, cell.bounds, materials.roomFloor, materials.wall, materials.ceiling, {}, door,
             room.backWallMaterial, materials.wall);
  addLamps(mesh, cell.id, lights, lightMaterials);

  RoomFrame frame;
  frame.x0 = room.plan.x0;
  frame.width = room.plan.x1 - room.plan.x0;
  frame.depth = kRoomDepth;
  frame.corridorWallZ = room.corridorWallZ;
  frame.awayFromCorridor = room.plan.north ? 1.0f : -1.0f;
  demo::furnishRoom(mesh, frame, materials, random, kDoorClearance);
  mesh.moveInto(cell);
  return cell;
}

Camera overviewCamera() {
  // From the south, 58 degrees down (atan(16 / 10)) onto the floor's centre;
  // 40 degrees of vertical field fits the 14 m x 10 m floor in 480 x 320.
  Camera camera;
  camera.name = "overview";
  camera.origin = Vec3(0.5f * kCorridorLength, 16.0f, -10.0f);
  camera.target = Vec3(0.5f * kCorridorLength, 0.0f, 0.0f);
  camera.up = Vec3(0.0f, 1.0f, 0.0f);
  camera.fovYDegrees = 40.0f;
  camera.width = 480;
  camera.height = 320;
  camera.cell = kDemoSkyCell;
  return camera;
}

// A camera per room, named as the room, standing just inside its door
// (where no furniture stands) and looking at the middle of the far wall;
// one at the corridor's west end, looking along it.
std::vector<Camera> interiorCameras(const std::vector<Room>& rooms, const Camera& overview) {
  std::vector<Camera> cameras;
  for (const Room& room : rooms) {
    const float inward = room.plan.north ? 1.0f : -1.0f;
    const Vec3 door(0.5f * (room.doorX0 + room.doorX1), 0.0f, room.corridorWallZ + inward * 0.6f);
    const Vec3 farWall(0.5f * (room.plan.x0 + room.plan.x1), 0.0f, room.farWallZ);
    cameras.push_back(standingCamera(room.plan.name, room.cell, 0.0f, door, farWall, overview.width, overview.height));
  }
  cameras.push_back(standingCamera("corridor", kDemoCorridorCell, 0.0f, Vec3(0.5f, 0.0f, 0.0f),
                                   Vec3(kCorridorLength, 0.0f, 0.0f), overview.width, overview.height));
  return cameras;
}

// The sky: above the whole floor (from the top of the cells' boxes), grown to
// hold the camera.
Bounds3 skyBounds(const Camera& camera) {
  const float outerZ = kCorridorHalfWidth + kRoomDepth;
  Bounds3 sky(Vec3(-kSkyMargin, kCellTop, -outerZ - kSkyMargin),
              Vec3(kCorridorLength + kSkyMargin, kCellTop + kSkyHeight, outerZ + kSkyMargin));
  sky.lo.x = std::min(sky.lo.x, camera.origin.x - 1.0f);
  sky.hi.x = std::max(sky.hi.x, camera.origin.x + 1.0f);
  sky.lo.z = std::min(sky.lo.z, camera.origin.z - 1.0f);
  sky.hi.z = std::max(sky.hi.z, camera.origin.z + 1.0f);
  return sky;
}

}  // namespace

void generateDemoBuilding(const std::string& storeDirectory, uint64_t seed, const PanelLighting& lighting) {
  if (const std::string problem = panelLightingProblem(lighting); !problem.empty()) throw std::invalid_argument(problem);
  DemoRandom random(seed);
  SceneStoreWriter writer(storeDirectory);
  writer.setMeta("generator", "demo");
  writer.setMeta("seed", std::to_string(seed));
  const Materials materials = addMaterials(writer);
  const std::vector<Room> rooms = planRooms(materials, random);
  const Bounds3 corridor(Vec3(0.0f, 0.0f, -kCorridorHalfWidth), Vec3(kCorridorLength, kCellTop, kCorridorHalfWidth));

  // Portals first: a cell file lists the portals touching it.
  for (const Room& room : rooms) writer.addPortal(kDemoCorridorCell, room.cell, doorRectangle(room));
  writer.addPortal(kDemoCorridorCell, kDemoSkyCell, topRectangle(corridor));
  for (const Room& room : rooms) writer.addPortal(room.cell, kDemoSkyCell, topRectangle(room.bounds));

  std::vector<AreaLight> lights;
  for (const Room& room : rooms)
    if (room.plan.lit)
      lights.push_back(ceilingLight(room.cell, 0.5f * (room.plan.x0 + room.plan.x1),
                                    0.5f * (room.corridorWallZ + room.farWallZ), room.lightSize));
  for (float x : kCorridorLightX) lights.push_back(ceilingLight(kDemoCorridorCell, x, 0.0f, kCorridorLightSize));
  PanelMaterials panels(writer, lighting, materials.light);
  std::vector<uint32_t> lightMaterials;
  for (AreaLight& light : lights) {
    lightMaterials.push_back(panels.light(light));
    light.id = writer.addLight(light);
  }

  // One cell in memory at a time, as a large building would be written.
  writer.writeCell(corridorCell(corridor, rooms, lights, lightMaterials, materials));
  for (const Room& room : rooms) writer.writeCell(roomCell(room, lights, lightMaterials, materials, random));
  const Camera camera = overviewCamera();
  CellContent sky;
  sky.id = kDemoSkyCell;
  sky.name = "sky";
  sky.bounds = skyBounds(camera);
  writer.writeCell(sky);

  writer.setCamera(camera);
  for (const Camera& inside : interiorCameras(rooms, camera)) writer.addCamera(inside);
  writer.commit();
}

}  // namespace portico
