#include "coordinator/cli/dashboard/plan_geometry.h"

#include <cmath>

#include "common/scene/store/floor_levels.h"
#include "common/scene/store/scene_store.h"
#include "coordinator/cli/plan_walls.h"
#include "coordinator/cli/scene_plan.h"

namespace portico::cli {

namespace {
constexpr float kSliceHeight = 1.5f;   // metres above the floor, as `scene plan` cuts walls

// Centimetres are plenty on a plan, and keep the page's JSON small.
double rounded(float metres) { return std::round(double(metres) * 100.0) / 100.0; }
}  // namespace

nlohmann::json planGeometry(const std::string& storeDirectory) {
  const SceneStore store = SceneStore::open(storeDirectory);
  const FloorLevels floors = findFloorLevels(store.cells());
  const std::vector<bool> drawn = cellsToDraw(store);
  Bounds3 frame;
  nlohmann::json list = nlohmann::json::array();
  for (size_t f = 0; f < floors.levels.size(); ++f) {
    nlohmann::json cells = nlohmann::json::array();
    std::vector<uint32_t> ids;
    for (const CellInfo& cell : store.cells()) {
      if (!drawn[cell.id] || floors.cellFloor[cell.id] != f) continue;
      ids.push_back(cell.id);
      frame.extend(cell.bounds);
      cells.push_back({cell.id, rounded(cell.bounds.lo.x), rounded(cell.bounds.lo.z), rounded(cell.bounds.hi.x),
                       rounded(cell.bounds.hi.z)});
    }
    nlohmann::json walls = nlohmann::json::array();
    for (const PlanSegment& s : sliceCells(store, ids, floors.levels[f] + kSliceHeight))
      walls.push_back({rounded(s.x0), rounded(s.z0), rounded(s.x1), rounded(s.z1)});
    list.push_back({{"floor", f}, {"level", rounded(floors.levels[f])}, {"cells", cells}, {"walls", walls}});
  }
  nlohmann::json bounds = frame.empty() ? nlohmann::json::array({0, 0, 1, 1})
                                        : nlohmann::json::array({rounded(frame.lo.x), rounded(frame.lo.z),
                                                                 rounded(frame.hi.x), rounded(frame.hi.z)});
  return {{"floors", list}, {"bounds", bounds}};
}

}  // namespace portico::cli
