// What the building importer has read and checked, before any of it is
// written: the input meshes (held in memory), materials, lights, the given
// cells and portals, the named cameras. Written either as its own cells
// (building_importer.cpp) or cut into voxel cells (voxel_cells.h).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/math.h"
#include "common/scene/import/quad_light.h"
#include "common/scene/store/scene_types.h"
#include "common/scene/store/site_location.h"

namespace portico {

struct ImportedMaterial {
  std::string name;
  Vec3 albedo;
  Vec3 emission;
  bool hiddenFromCamera = false;   // kept when a scene store is re-cut
  std::string albedoTexture;       // the image file (copied into the store), or empty
  Vec3 transmittance;              // thin glass when above 0 (Material::transmittance)
  float ior = 1.5f;
};

// One object of a building.json, or one part of a mesh file.
struct ImportedObject {
  std::string label;                // how messages name it
  uint32_t cell = 0;                // index into ImportedScene::cells
  uint32_t material = 0;            // index into ImportedScene::materials
  std::vector<float> positions;     // xyz per vertex
  std::vector<uint32_t> indices;    // 3 per triangle, front = cross(v1 - v0, v2 - v0)
  std::vector<float> uvs;           // uv per vertex when its material is textured, else empty
  size_t triangleCount() const { return indices.size() / 3; }
  Vec3 vertex(uint32_t i) const {
    const float* p = &positions[3 * size_t{i}];
    return {p[0], p[1], p[2]};
  }
};

// An emitter: a parallelogram or a triangle (corner, corner + edge1,
// corner + edge2) whose triangles are also in `objects`.
struct ImportedLight {
  std::string label;
  uint32_t cell = 0;                // index into ImportedScene::cells
  Parallelogram shape;
  Vec3 radiance;
  LightShape kind = LightShape::Parallelogram;
  // A point luminaire's candela distribution (shape: corner = its point,
  // edge1 its nadir, edge2 its C0 direction; radiance per candela).
  std::shared_ptr<const LuminousIntensity> intensity;
  LuminousOpening opening;   // a point luminaire's luminous opening
  // The store's record of it (id left to the writer).
  AreaLight areaLight() const {
    AreaLight light;
    light.cell = cell;
    light.shape = kind;
    light.corner = shape.corner;
    light.edge1 = shape.edge1;
    light.edge2 = shape.edge2;
    light.radiance = radiance;
    light.intensity = intensity;
    light.opening = opening;
    return light;
  }
};

struct ImportedCell {
  std::string name;
  Bounds3 bounds;
};

struct ImportedPortal {
  uint32_t cellA = 0, cellB = 0;
  std::vector<Vec3> polygon;
};

struct ImportedScene {
  std::vector<ImportedMaterial> materials;
  std::vector<ImportedObject> objects;
  std::vector<ImportedCell> cells;       // the given cells, or one around everything
  std::vector<ImportedPortal> portals;
  std::vector<ImportedLight> lights;
  std::vector<Camera> cameras;           // the default first; cell: index into cells
  std::optional<SiteLocation> site;      // where the building stands, if known
  Bounds3 bounds;                        // triangles, camera origins and given cells, not padded
  uint64_t degenerateTrianglesDropped = 0;   // zero-area triangles of the meshes, left out
  uint64_t triangleCount() const {
    uint64_t count = 0;
    for (const ImportedObject& object : objects) count += object.triangleCount();
    return count;
  }
};

}  // namespace portico
