#include "common/scene/import/room_lighting.h"

#include <algorithm>
#include <cmath>

#include "common/photometry/lamp_colour.h"

namespace portico {

namespace {

// As python/portico_ifc/lights_cameras.py gives a space.
constexpr double kPanelFraction = 0.04;          // of the floor area
constexpr double kPanelLumensPerSquareMetre = 250.0;
const Vec3 kPanelColour(12.0f, 11.0f, 9.5f);
constexpr float kBelowCeiling = 0.05f;
constexpr float kEyeHeight = 1.6f;
constexpr float kMinRoomFloorArea = 1.0f;        // m^2: a room's panel is never smaller than this floor's

}  // namespace

void addRoomLamps(const FoundRooms& rooms, ImportedScene& scene) {
  for (const FoundRoom& room : rooms.roomAir) {
    const double area = std::max<double>(room.floorArea, kMinRoomFloorArea);
    const float side = float(std::sqrt(kPanelFraction * area));
    const Vec3 extent = room.air.diagonal();
    // Inside the clear square under the ceiling, and well inside the room's box.
    const float halfX = std::min({0.5f * side, 0.95f * room.clearHalfWidth, 0.4f * extent.x});
    const float halfZ = std::min({0.5f * side, 0.95f * room.clearHalfWidth, 0.4f * extent.z});
    const float y = std::max(room.ceiling - kBelowCeiling, room.floor + 0.5f * (room.ceiling - room.floor));
    // edge1 x edge2 points down: the panel emits into the room below it.
    const Parallelogram quad{Vec3(room.centre.x - halfX, y, room.centre.z - halfZ), Vec3(2 * halfX, 0, 0),
                             Vec3(0, 0, 2 * halfZ)};
    const Vec3 radiance = radianceOfLumens(kPanelLumensPerSquareMetre * area, kPanelColour,
                                           double(4 * halfX * halfZ));
    ImportedMaterial material;
    material.name = "lamp " + room.name;
    material.emission = radiance;
    scene.materials.push_back(material);
    ImportedObject object;
    object.label = material.name;
    object.material = uint32_t(scene.materials.size() - 1);
    for (const Vec3& p : {quad.corner, quad.corner + quad.edge1, quad.corner + quad.edge1 + quad.edge2,
                          quad.corner + quad.edge2})
      object.positions.insert(object.positions.end(), {p.x, p.y, p.z});
    object.indices = {0, 1, 2, 0, 2, 3};
    scene.objects.push_back(std::move(object));
    scene.lights.push_back(ImportedLight{material.name, 0, quad, radiance, LightShape::Parallelogram, nullptr});
  }
}

void addRoomCameras(const FoundRooms& rooms, bool keepDefault, ImportedScene& scene) {
  std::vector<Camera> cameras;
  for (const FoundRoom& room : rooms.roomAir) {
    const float height = room.ceiling - room.floor;
    // Eye height, or half way up a room too low for it.
    float y = height < kEyeHeight + 0.3f ? room.floor + 0.5f * height : room.floor + kEyeHeight;
    y = std::clamp(y, room.floor + 0.05f, room.ceiling - 0.05f);
    Camera camera;
    camera.name = room.name;
    camera.origin = Vec3(room.centre.x, y, room.centre.z);
    // Across the room: to the far corner of its air's box, a metre over the floor.
    float farthest = -1.0f;
    for (float x : {room.air.lo.x, room.air.hi.x})
      for (float z : {room.air.lo.z, room.air.hi.z}) {
        const float d = std::hypot(x - room.centre.x, z - room.centre.z);
        if (d > farthest) {
          farthest = d;
          camera.target = Vec3(x, room.floor + 1.0f, z);
        }
      }
    camera.up = Vec3(0, 1, 0);
    camera.fovYDegrees = 70.0f;
    camera.width = 512;
    camera.height = 384;
    cameras.push_back(camera);
  }
  const auto at = scene.cameras.begin() + (keepDefault && !scene.cameras.empty() ? 1 : 0);
  scene.cameras.insert(at, cameras.begin(), cameras.end());
}

}  // namespace portico
