// Daylight's way out of the building. A ray towards the sky (a shadow ray
// to the sun or through an opening, or a daylight photon's way back) goes
// on through the outdoor cells beyond its opening until it leaves the
// building, and whatever it meets there shadows. Outdoor cells that hold
// no geometry (the generated buildings' facades and sky) cannot block it:
// it crosses them here, by their portals alone, with no lease of theirs,
// and goes to a cell only where that cell may hold something in its way.
#pragma once

#include <cstdint>
#include <unordered_map>
#include <vector>

#include "common/ray.h"
#include "common/scene/store/scene_store.h"
#include "common/transport/cell_portals.h"

namespace portico {

class OutdoorPassage {
 public:
  explicit OutdoorPassage(const SceneStore& scene);
  bool outdoors(uint32_t cell) const { return cell < outdoor_.size() && outdoor_[cell]; }

  struct End {
    bool sky = false;     // left the building: nothing was in the way
    uint32_t cell = 0;    // otherwise the cell to trace it in next,
    float tMin = 0;       // from here on
  };
  // Follows `ray`, which enters `cell` at ray.tMin, across outdoor cells
  // without geometry (with the tracer's rules: portals it moves out of,
  // restarting just before each).
  End follow(Ray ray, uint32_t cell) const;

 private:
  struct EmptyCell {
    CellPortals portals;
    Bounds3 bounds;
  };
  std::vector<bool> outdoor_;
  std::unordered_map<uint32_t, EmptyCell> emptyOutdoorCells_;
};

}  // namespace portico
