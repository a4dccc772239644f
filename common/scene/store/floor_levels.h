// A building's floors as `portico scene info` counts them and `portico scene
// plan` draws them: the distinct heights at which cells with triangles start
// (their bounds' lo.y), heights within kFloorMergeDistance of a floor's
// lowest one merged into it (a raised platform or a sunken step is no floor).
#pragma once

#include <cstdint>
#include <vector>

#include "common/scene/store/scene_store.h"
#include "common/scene/store/scene_types.h"

namespace portico {

constexpr float kFloorMergeDistance = 0.5f;   // metres

struct FloorLevels {
  std::vector<float> levels;        // each floor's lowest cell bottom, ascending
  std::vector<uint32_t> cellFloor;  // per cell id: the floor it starts on
};

// Cells without triangles (door cells, an empty voxel, the sky) do not make
// floors. Every cell is put on the highest floor starting at or below its
// bottom (floor 0 when it starts below every floor).
FloorLevels findFloorLevels(const std::vector<CellInfo>& cells);

// The store's meta "floors" when its generator wrote one, else the number
// of levels findFloorLevels finds.
uint32_t floorCount(const SceneStore& store);

// Whether the store's cells are voxels of a uniform grid (scene import
// --grid) rather than rooms.
bool hasVoxelCells(const SceneStore& store);

// "layer" for a store cut into voxels (its levels are slabs of voxels, not
// storeys), else "floor": the word `scene info` and `scene plan` use.
const char* levelWord(const SceneStore& store);

}  // namespace portico
