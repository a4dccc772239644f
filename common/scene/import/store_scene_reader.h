// Reads a scene store back as an ImportedScene, so that `portico scene
// import --grid RG STORE OUT` can re-cut a generated (or imported) building
// into uniform voxel cells: the same building, topological or uniform cells,
// as the paper compares. Every cell's geometry is held in memory at once.
#pragma once

#include <string>

#include "common/scene/import/imported_scene.h"

namespace portico {

// Whether `path` is a scene store directory (it holds scene.db).
bool isSceneStore(const std::string& path);

// One object per (cell, material); the store's materials, lights, portals,
// cells and camera. Throws std::runtime_error naming the store and problem.
ImportedScene sceneFromStore(const std::string& directory);

}  // namespace portico
