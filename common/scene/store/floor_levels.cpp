// Floor levels by clustering the bottoms of the cells that hold geometry.
#include "common/scene/store/floor_levels.h"

#include <algorithm>
#include <charconv>

namespace portico {

FloorLevels findFloorLevels(const std::vector<CellInfo>& cells) {
  std::vector<float> bottoms;
  for (const CellInfo& cell : cells)
    if (cell.triangleCount > 0) bottoms.push_back(cell.bounds.lo.y);
  if (bottoms.empty())   // a store without geometry: its cells still have floors
    for (const CellInfo& cell : cells) bottoms.push_back(cell.bounds.lo.y);
  std::sort(bottoms.begin(), bottoms.end());

  FloorLevels floors;
  // Measured from the floor's lowest bottom, not the previous one, so a
  // staircase of cells 0.3 m apart does not chain into one floor.
  for (float bottom : bottoms)
    if (floors.levels.empty() || bottom - floors.levels.back() > kFloorMergeDistance) floors.levels.push_back(bottom);

  // A cell is on the highest floor starting at or below its bottom, give or
  // take a centimetre of rounding; for a cell with triangles that is the
  // cluster its bottom went into.
  constexpr float kRounding = 0.01f;
  floors.cellFloor.reserve(cells.size());
  for (const CellInfo& cell : cells) {
    const auto above =
        std::upper_bound(floors.levels.begin(), floors.levels.end(), cell.bounds.lo.y + kRounding);
    const auto floor = above == floors.levels.begin() ? 0 : above - floors.levels.begin() - 1;
    floors.cellFloor.push_back(static_cast<uint32_t>(floor));
  }
  return floors;
}

uint32_t floorCount(const SceneStore& store) {
  if (auto it = store.meta().find("floors"); it != store.meta().end()) {
    uint32_t floors = 0;
    const std::string& text = it->second;
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), floors);
    if (error == std::errc() && end == text.data() + text.size() && floors > 0) return floors;
  }
  return static_cast<uint32_t>(findFloorLevels(store.cells()).levels.size());
}

bool hasVoxelCells(const SceneStore& store) {
  const auto it = store.meta().find("cells");
  return it != store.meta().end() && it->second.rfind("grid", 0) == 0;
}

const char* levelWord(const SceneStore& store) { return hasVoxelCells(store) ? "layer" : "floor"; }

}  // namespace portico
