// Furniture for the demo building: beds, sofas, bookshelves, cabinets,
// tables and chairs made of boxes, placed at seeded random spots in a room.
// Internal to demo_generator.cpp; split out to keep each file one concern.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>

#include "common/math.h"
#include "common/scene/generator/mesh_builder.h"

namespace portico::demo {

// Seeded randomness that is the same on every platform: std::mt19937_64 is
// fully specified, but std::uniform_real_distribution is not, so floats are
// made from the engine's bits by hand. Same seed, same building, same bytes.
class DemoRandom {
 public:
  explicit DemoRandom(uint64_t seed) : engine_(seed) {}
  float uniform(float lo, float hi) {
    const double unit = static_cast<double>(engine_() >> 11) * 0x1.0p-53;
    return lo + static_cast<float>(unit) * (hi - lo);
  }
  // A length rounded to the centimetre, so that the catalogue reads nicely.
  float centimetres(float lo, float hi) { return std::round(uniform(lo, hi) * 100.0f) / 100.0f; }
  uint32_t index(uint32_t count) { return static_cast<uint32_t>(engine_() % count); }
  bool chance(float probability) { return uniform(0.0f, 1.0f) < probability; }

 private:
  std::mt19937_64 engine_;
};

struct DemoMaterials {
  uint32_t roomFloor, corridorFloor, wall;
  uint32_t accentWalls[3];
  uint32_t wood, darkWood, cabinet, metal;
  uint32_t fabrics[3];
  uint32_t books[3];
  uint32_t light;
};

// A room seen from its door: u runs along the corridor wall (world +x from
// x0), v runs away from the corridor (depth), y is up. North rooms have
// world z = corridorWallZ + v, south rooms corridorWallZ - v.
struct RoomFrame {
  float x0 = 0, width = 0, depth = 0;
  float corridorWallZ = 0;
  float awayFromCorridor = 1;   // +1 (north) or -1 (south)

  Bounds3 toWorld(float u0, float u1, float y0, float y1, float v0, float v1) const {
    const float za = corridorWallZ + awayFromCorridor * v0;
    const float zb = corridorWallZ + awayFromCorridor * v1;
    return Bounds3(Vec3(x0 + u0, y0, std::min(za, zb)), Vec3(x0 + u1, y1, std::max(za, zb)));
  }
};

// Adds a few pieces of furniture to a room, keeping a strip of
// `doorClearance` metres along the corridor wall free so the door is open.
void furnishRoom(MeshBuilder& mesh, const RoomFrame& room, const DemoMaterials& materials, DemoRandom& random,
                 float doorClearance);

}  // namespace portico::demo
