// `portico scene export STORE -o FILE.obj`: the store's triangles as
// Wavefront OBJ + MTL, objects per cell and material (lamps one object each,
// export_groups.h, so that `portico scene import FILE.obj` takes them back
// as lights), every material's albedo as Kd and emission as Ke; portals and
// cameras as comments. For Blender, any viewer, and other renderers.
// FILE.glb and FILE.gltf go to the glTF writer (scene_export_gltf.h),
// FILE.rad to the Radiance writer (scene_export_radiance.h).
#pragma once

#include <cstdint>
#include <string>

#include "common/job/job_settings.h"
#include "common/math.h"

namespace portico::cli {

struct ExportSummary {
  uint64_t triangles = 0;
  Bounds3 bounds;
  uint64_t polygons = 0;     // Radiance: polygons written (a lamp quad is one)
  uint32_t materials = 0;    // Radiance: material definitions written
  std::string skyFile;       // Radiance: the daylight file written, if any
  uint32_t luminaires = 0;   // Radiance: IES point luminaires written as sources (a data file each)
};

// Throws std::runtime_error naming the file when it cannot be written or
// the extension is not .obj.
ExportSummary exportStoreObj(const std::string& store, const std::string& objPath);

// `daylight` (--sky, --sun, ...) is for a Radiance export only: refused
// with another format.
int runSceneExport(const std::string& store, const std::string& output, const DaylightSettings& daylight = {});

}  // namespace portico::cli
