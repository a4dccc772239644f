// Plain records of a scene store's catalogue (scene.db).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/math.h"

namespace portico {

struct Material {
  uint32_t id = 0;
  std::string name;
  Vec3 albedo;     // linear RGB reflectance in [0,1]; Lambertian BRDF = albedo / pi
  Vec3 emission;   // RGB radiance, one-sided (front = geometric normal side)
  // Cut-away: camera rays pass through it (it still blocks and reflects
  // light); lets a view from above show a room whose ceiling still lights it.
  bool hiddenFromCamera = false;
  bool emissive() const { return maxComponent(emission) > 0.0f; }
};

// A parallelogram area light: corner + s*edge1 + t*edge2, s,t in [0,1].
// It emits on the side of cross(edge1, edge2). Its triangles are also part
// of its cell's geometry (with an emissive material), so rays can hit it.
struct AreaLight {
  uint32_t id = 0;
  uint32_t cell = 0;
  Vec3 corner, edge1, edge2;
  Vec3 radiance;
  Vec3 normal() const { return normalize(cross(edge1, edge2)); }
  float area() const { return length(cross(edge1, edge2)); }
  Vec3 power() const { return radiance * (kPi * area()); }   // Phi = pi A L per channel
  Vec3 center() const { return corner + (edge1 + edge2) * 0.5f; }
};

struct CellInfo {
  uint32_t id = 0;
  std::string name;
  Bounds3 bounds;
  uint64_t triangleCount = 0;
  uint64_t byteCount = 0;      // size of the cell file
  std::string file;            // relative to the store directory
};

// A planar convex polygon joining two cells.
struct Portal {
  uint32_t id = 0;
  uint32_t cellA = 0, cellB = 0;
  std::vector<Vec3> polygon;
};

struct Camera {
  Vec3 origin, target, up{0, 1, 0};
  float fovYDegrees = 60.0f;   // full vertical field of view
  uint32_t width = 256, height = 256;
  uint32_t cell = 0;           // the cell containing origin
};

}  // namespace portico
