// The named cameras the generators put inside a building: a person standing
// in a room's doorway looking into the room, or at a corridor's end looking
// along it.
#pragma once

#include <string>

#include "common/scene/store/scene_types.h"

namespace portico {

constexpr float kStandingEyeHeight = 1.6f;   // above the floor
// The point looked at is this much above the floor: a little below the eye,
// so the view holds more floor and furniture than ceiling.
constexpr float kStandingLookHeight = 1.2f;
constexpr float kStandingFovYDegrees = 60.0f;

// The eye above `from`, looking towards the point above `to` (both given at
// any height: only x and z are used), in `cell`, whose floor is at floorY.
inline Camera standingCamera(std::string name, uint32_t cell, float floorY, const Vec3& from, const Vec3& to,
                             uint32_t width, uint32_t height) {
  Camera camera;
  camera.name = std::move(name);
  camera.origin = Vec3(from.x, floorY + kStandingEyeHeight, from.z);
  camera.target = Vec3(to.x, floorY + kStandingLookHeight, to.z);
  camera.up = Vec3(0.0f, 1.0f, 0.0f);
  camera.fovYDegrees = kStandingFovYDegrees;
  camera.width = width;
  camera.height = height;
  camera.cell = cell;
  return camera;
}

}  // namespace portico
