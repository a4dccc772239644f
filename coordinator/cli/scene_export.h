// `portico scene export STORE -o FILE.obj`: the store's triangles as
// Wavefront OBJ + MTL, objects per cell and material (lamps one object each,
// export_groups.h, so that `portico scene import FILE.obj` takes them back
// as lights), every material's albedo as Kd and emission as Ke; portals and
// cameras as comments. For Blender, any viewer, and other renderers.
// FILE.glb and FILE.gltf go to the glTF writer (scene_export_gltf.h).
#pragma once

#include <cstdint>
#include <string>

#include "common/math.h"

namespace portico::cli {

struct ExportSummary {
  uint64_t triangles = 0;
  Bounds3 bounds;
};

// Throws std::runtime_error naming the file when it cannot be written or
// the extension is not .obj.
ExportSummary exportStoreObj(const std::string& store, const std::string& objPath);

int runSceneExport(const std::string& store, const std::string& output);

}  // namespace portico::cli
