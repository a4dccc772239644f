// `portico scene export STORE -o FILE.glb|FILE.gltf`: the store as glTF 2.0
// (binary .glb, or .gltf with its buffer in FILE.bin beside it).
//  * One node per cell (named after it; extras: portico_cell, min, max),
//    its mesh one primitive per material, and each lamp (two triangles
//    forming a parallelogram, else one emissive triangle) a primitive of its
//    own, so that `portico scene import FILE.glb` reads each back as a light.
//  * Materials: albedo as the base colour (metallic 0, roughness 1);
//    radiance as emissiveFactor x KHR_materials_emissive_strength.
//  * The camera as a glTF perspective camera on a node of its own (extras:
//    width, height, cell, target, up); portals and the light records as the
//    scene's extras (portico_portals, portico_lights).
#pragma once

#include <string>

#include "coordinator/cli/scene_export.h"

namespace portico::cli {

bool isGltfPath(const std::string& path);   // *.glb or *.gltf

// Throws std::runtime_error naming the file when it cannot be written or
// the extension is neither .glb nor .gltf.
ExportSummary exportStoreGltf(const std::string& store, const std::string& path);

}  // namespace portico::cli
