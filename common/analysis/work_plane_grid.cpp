// The work-plane grid: per cell, a plan index of its triangles (buckets in
// x-z), the floor found from it, then the lattice filtered point by point.
#include "common/analysis/work_plane_grid.h"

#include <fmt/format.h>
#include <fnmatch.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <stdexcept>

#include "common/scene/store/cell_geometry.h"
#include "common/scene/store/floor_levels.h"
#include "common/scene/store/mesh_slice.h"
#include "common/transport/daylight_openings.h"

namespace portico {

namespace {

constexpr float kLevelNormal = 0.99f;      // |n.y| above this: a level triangle
constexpr float kLevelTolerance = 0.02f;   // metres: heights closer than this are one level
constexpr float kWallSliceHeight = 1.5f;   // metres above the floor, as `scene plan` cuts walls
constexpr float kPlaneTolerance = 0.02f;   // the free vertical starts this far below the work plane
constexpr float kEdgeSlack = 1e-3f;        // metres: a point exactly `inset` from an edge is kept
constexpr int kCircleSamples = 16;
constexpr float kBucketSize = 0.5f;        // metres, the plan index's squares
constexpr double kMinCoveredShare = 0.5;   // of a room's floor under a ceiling or roof

bool chosen(const CellInfo& cell, uint32_t floor, const WorkPlaneGridOptions& options) {
  if (!options.cells.empty() && std::find(options.cells.begin(), options.cells.end(), cell.id) == options.cells.end())
    return false;
  if (!options.floors.empty() && std::find(options.floors.begin(), options.floors.end(), floor) == options.floors.end())
    return false;
  if (options.roomNames.empty()) return true;
  return std::any_of(options.roomNames.begin(), options.roomNames.end(), [&](const std::string& pattern) {
    return fnmatch(pattern.c_str(), cell.name.c_str(), 0) == 0;
  });
}

// A cell's triangles indexed by the plan squares their x-z bounds touch,
// and the walls (slice segments) indexed likewise, grown by the inset.
class PlanIndex {
 public:
  explicit PlanIndex(const MeshView& mesh, const Bounds3& bounds) : mesh_(mesh) {
    lo_x_ = bounds.lo.x, lo_z_ = bounds.lo.z;
    columns_ = std::max(1, int(std::ceil((bounds.hi.x - bounds.lo.x) / kBucketSize)));
    rows_ = std::max(1, int(std::ceil((bounds.hi.z - bounds.lo.z) / kBucketSize)));
    triangles_.resize(size_t(columns_) * rows_);
    for (uint32_t t = 0; t < mesh.triangleCount; ++t) {
      const Bounds3 box = mesh.triangleBounds(t);
      forSquares(box.lo.x, box.lo.z, box.hi.x, box.hi.z, [&](size_t s) { triangles_[s].push_back(t); });
    }
  }

  void addWalls(std::vector<PlanSegment> walls, float reach) {
    walls_ = std::move(walls);
    wallSquares_.assign(triangles_.size(), {});
    for (uint32_t i = 0; i < walls_.size(); ++i) {
      const PlanSegment& w = walls_[i];
      forSquares(std::min(w.x0, w.x1) - reach, std::min(w.z0, w.z1) - reach, std::max(w.x0, w.x1) + reach,
                 std::max(w.z0, w.z1) + reach, [&](size_t s) { wallSquares_[s].push_back(i); });
    }
  }

  // The triangles whose x-z bounds may hold (x, z).
  const std::vector<uint32_t>& trianglesAt(float x, float z) const { return triangles_[square(x, z)]; }

  // The plan distance from (x, z) to the nearest wall within reach (or reach).
  float wallDistance(float x, float z, float reach) const {
    float nearest = reach;
    for (uint32_t i : wallSquares_[square(x, z)]) nearest = std::min(nearest, segmentDistance(walls_[i], x, z));
    return nearest;
  }

  // The height at which the vertical through (x, z) meets triangle t, if it
  // does (a triangle standing on edge in plan is never met).
  bool verticalHit(uint32_t t, float x, float z, float& y) const {
    Vec3 a, b, c;
    mesh_.triangle(t, a, b, c);
    const double d = double(b.x - a.x) * (c.z - a.z) - double(c.x - a.x) * (b.z - a.z);
    if (std::abs(d) < 1e-12) return false;
    const double u = (double(x - a.x) * (c.z - a.z) - double(c.x - a.x) * (z - a.z)) / d;
    const double v = (double(b.x - a.x) * (z - a.z) - double(x - a.x) * (b.z - a.z)) / d;
    if (u < 0 || v < 0 || u + v > 1) return false;
    y = float(a.y + u * (b.y - a.y) + v * (c.y - a.y));
    return true;
  }

 private:
  size_t square(float x, float z) const {
    const int i = std::clamp(int(std::floor((x - lo_x_) / kBucketSize)), 0, columns_ - 1);
    const int j = std::clamp(int(std::floor((z - lo_z_) / kBucketSize)), 0, rows_ - 1);
    return size_t(j) * columns_ + i;
  }
  template <typename Visit>
  void forSquares(float x0, float z0, float x1, float z1, Visit&& visit) const {
    const int i0 = std::clamp(int(std::floor((x0 - lo_x_) / kBucketSize)), 0, columns_ - 1);
    const int i1 = std::clamp(int(std::floor((x1 - lo_x_) / kBucketSize)), 0, columns_ - 1);
    const int j0 = std::clamp(int(std::floor((z0 - lo_z_) / kBucketSize)), 0, rows_ - 1);
    const int j1 = std::clamp(int(std::floor((z1 - lo_z_) / kBucketSize)), 0, rows_ - 1);
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) visit(size_t(j) * columns_ + i);
  }
  static float segmentDistance(const PlanSegment& s, float x, float z) {
    const double dx = s.x1 - s.x0, dz = s.z1 - s.z0, length2 = dx * dx + dz * dz;
    double t = length2 > 0 ? ((x - s.x0) * dx + (z - s.z0) * dz) / length2 : 0;
    t = std::clamp(t, 0.0, 1.0);
    return float(std::hypot(s.x0 + t * dx - x, s.z0 + t * dz - z));
  }

  const MeshView& mesh_;
  float lo_x_ = 0, lo_z_ = 0;
  int columns_ = 1, rows_ = 1;
  std::vector<std::vector<uint32_t>> triangles_;
  std::vector<PlanSegment> walls_;
  std::vector<std::vector<uint32_t>> wallSquares_;
};

// The floor: the level (within kLevelTolerance) of up-facing level
// triangles with the most area in the cell's lower half.
struct Floor {
  bool found = false;
  float height = 0;
  double area = 0;
  std::vector<bool> isFloor;   // per triangle
  Bounds3 extent;              // of the floor's triangles
};

Floor findFloor(const MeshView& mesh, const Bounds3& bounds) {
  const float halfway = 0.5f * (bounds.lo.y + bounds.hi.y);
  struct Level {
    uint32_t triangle;
    float y;
    double area;
  };
  std::vector<Level> levels;   // the up-facing level triangles of the lower half
  for (uint32_t t = 0; t < mesh.triangleCount; ++t) {
    const Vec3 n = mesh.geometricNormal(t);
    const float size = length(n);
    if (size <= 0 || n.y < kLevelNormal * size) continue;
    Vec3 a, b, c;
    mesh.triangle(t, a, b, c);
    const float y = (a.y + b.y + c.y) / 3.0f;
    if (y <= halfway) levels.push_back({t, y, 0.5 * size});
  }
  std::sort(levels.begin(), levels.end(), [](const Level& a, const Level& b) { return a.y < b.y; });
  Floor floor;
  size_t first = 0, end = 0;   // the floor's cluster: levels[first, end)
  for (size_t i = 0; i < levels.size();) {   // clusters measured from their lowest height
    size_t j = i;
    double area = 0;
    while (j < levels.size() && levels[j].y - levels[i].y <= kLevelTolerance) area += levels[j++].area;
    if (area > floor.area) floor.area = area, floor.height = levels[i].y, floor.found = true, first = i, end = j;
    i = j;
  }
  floor.isFloor.assign(mesh.triangleCount, false);
  for (size_t k = first; k < end; ++k) {
    floor.isFloor[levels[k].triangle] = true;
    floor.extent.extend(mesh.triangleBounds(levels[k].triangle));
  }
  return floor;
}

// The lattice positions along one axis: `spacing` apart, centred in
// [lo + inset, hi - inset]; none when that span is empty.
std::vector<float> latticeAlong(float lo, float hi, float spacing, float inset) {
  const double span = double(hi) - lo - 2.0 * inset;
  if (span < -2 * kEdgeSlack) return {};
  const int count = int(std::floor(std::max(0.0, span) / spacing + 1e-6)) + 1;
  const double first = lo + inset + 0.5 * (span - double(count - 1) * spacing);
  std::vector<float> positions;
  for (int k = 0; k < count; ++k) positions.push_back(float(first + double(k) * spacing));
  return positions;
}

// A polygon in plan (x, z pairs).
using PlanPolygon = std::vector<std::pair<float, float>>;

bool insidePlanPolygon(const PlanPolygon& polygon, float x, float z) {
  bool inside = false;   // crossing number of a ray towards +x
  for (size_t i = 0, j = polygon.size() - 1; i < polygon.size(); j = i++) {
    const auto [xi, zi] = polygon[i];
    const auto [xj, zj] = polygon[j];
    if ((zi > z) != (zj > z) && x < xi + (z - zi) * (xj - xi) / (zj - zi)) inside = !inside;
  }
  return inside;
}

// The portals of `cell` that open upwards into another indoor cell (a
// gallery or mezzanine over the room, the voxel cell above), above the work
// plane at `plane`, in plan.
std::vector<PlanPolygon> indoorOpeningsAbove(const SceneStore& store, uint32_t cell, float plane) {
  std::vector<PlanPolygon> openings;
  for (const Portal& portal : store.portals()) {
    if (portal.cellA != cell && portal.cellB != cell) continue;
    const uint32_t other = portal.cellA == cell ? portal.cellB : portal.cellA;
    if (isOutdoorCell(store.cells()[other].name) || portal.polygon.size() < 3) continue;
    Vec3 normal, centre;
    for (size_t i = 0; i < portal.polygon.size(); ++i) {
      normal += cross(portal.polygon[i], portal.polygon[(i + 1) % portal.polygon.size()]);
      centre += portal.polygon[i];
    }
    centre = centre / float(portal.polygon.size());
    if (!(std::abs(normal.y) > 0.5f * length(normal)) || centre.y <= plane) continue;   // not a floor above
    PlanPolygon polygon;
    for (const Vec3& v : portal.polygon) polygon.push_back({v.x, v.z});
    openings.push_back(std::move(polygon));
  }
  return openings;
}

class RoomGrid {
 public:
  RoomGrid(const CellGeometry& cell, const Floor& floor, const WorkPlaneGridOptions& options,
           std::vector<PlanPolygon> openingsAbove)
      : mesh_(cell.mesh()),
        index_(cell.mesh(), cell.bounds()),
        floor_(floor),
        options_(options),
        openingsAbove_(std::move(openingsAbove)) {
    std::vector<PlanSegment> walls;
    sliceMesh(mesh_, floor.height + kWallSliceHeight, walls);
    index_.addWalls(std::move(walls), options.inset);
  }

  // Appends the kept points; returns false when the cell is no room (its
  // floor mostly under the open sky).
  bool place(std::vector<Vec3>& points) const {
    const std::vector<float> xs = latticeAlong(floor_.extent.lo.x, floor_.extent.hi.x, options_.spacing, 0.0f);
    const std::vector<float> zs = latticeAlong(floor_.extent.lo.z, floor_.extent.hi.z, options_.spacing, 0.0f);
    // Coverage on a lattice over the whole floor, before the inset.
    size_t onFloor = 0, covered = 0;
    for (float z : zs)
      for (float x : xs)
        if (overFloor(x, z)) ++onFloor, covered += coveredAbove(x, z) ? 1 : 0;
    if (onFloor == 0 || double(covered) < kMinCoveredShare * double(onFloor)) return false;

    const float plane = floor_.height + options_.height;
    for (float z : latticeAlong(floor_.extent.lo.z, floor_.extent.hi.z, options_.spacing, options_.inset))
      for (float x : latticeAlong(floor_.extent.lo.x, floor_.extent.hi.x, options_.spacing, options_.inset))
        if (insetFromEdges(x, z) && index_.wallDistance(x, z, options_.inset) >= options_.inset - kEdgeSlack &&
            verticalFree(x, z, plane - kPlaneTolerance, plane + kHeadroom) && indoors(x, z))
          points.push_back(Vec3(x, plane, z));
    return true;
  }

 private:
  bool overFloor(float x, float z) const {
    float y;
    for (uint32_t t : index_.trianglesAt(x, z))
      if (floor_.isFloor[t] && index_.verticalHit(t, x, z, y)) return true;
    return false;
  }
  bool insetFromEdges(float x, float z) const {
    if (!overFloor(x, z)) return false;
    const float radius = options_.inset - kEdgeSlack;
    for (int k = 0; k < kCircleSamples; ++k) {
      const double angle = 2.0 * M_PI * k / kCircleSamples;
      if (!overFloor(x + radius * float(std::cos(angle)), z + radius * float(std::sin(angle)))) return false;
    }
    return true;
  }
  // No triangle of the cell meets the vertical through (x, z) between y0 and y1.
  bool verticalFree(float x, float z, float y0, float y1) const {
    float y;
    for (uint32_t t : index_.trianglesAt(x, z))
      if (index_.verticalHit(t, x, z, y) && y > y0 && y < y1) return false;
    return true;
  }
  // The point on the work plane at (x, z) is under a ceiling or roof of
  // the cell, or under an opening into an indoor cell above. Not so: it
  // lies outside the building's envelope though inside the cell's box,
  // as where a pitched roof comes down lower than the work plane (FZK-Haus'
  // attic gallery at its eaves: the points 4 cm over the roof's outer face
  // saw the open sky, daylight factors of 100 % and more).
  bool indoors(float x, float z) const {
    if (coveredAbove(x, z)) return true;
    return std::any_of(openingsAbove_.begin(), openingsAbove_.end(),
                       [&](const PlanPolygon& opening) { return insidePlanPolygon(opening, x, z); });
  }
  // Some triangle of the cell (a ceiling, a roof) lies above the work plane at (x, z).
  bool coveredAbove(float x, float z) const {
    const float plane = floor_.height + options_.height;
    float y;
    for (uint32_t t : index_.trianglesAt(x, z))
      if (!floor_.isFloor[t] && index_.verticalHit(t, x, z, y) && y > plane) return true;
    return false;
  }

  const MeshView& mesh_;
  PlanIndex index_;
  const Floor& floor_;
  const WorkPlaneGridOptions& options_;
  const std::vector<PlanPolygon> openingsAbove_;
};

void checkOptions(const SceneStore& store, const FloorLevels& floors, const WorkPlaneGridOptions& options) {
  const auto positive = [](float value, const char* name) {
    if (!std::isfinite(value) || value <= 0)
      throw std::runtime_error(fmt::format("--grid-{}: {} is not a positive number of metres", name, value));
  };
  positive(options.height, "height");
  positive(options.spacing, "spacing");
  if (!std::isfinite(options.inset) || options.inset < 0)
    throw std::runtime_error(fmt::format("--grid-inset: {} is not a number of metres >= 0", options.inset));
  for (uint32_t cell : options.cells)
    if (cell >= store.cells().size())
      throw std::runtime_error(fmt::format("--grid-cells: scene store {} has no cell {} (it has {})",
                                           store.directory(), cell, store.cells().size()));
  for (uint32_t floor : options.floors)
    if (floor >= floors.levels.size())
      throw std::runtime_error(fmt::format("--grid-floors: scene store {} has no {} {} (it has {})", store.directory(),
                                           levelWord(store), floor, floors.levels.size()));
}

}  // namespace

std::optional<RoomFloor> findRoomFloor(const SceneStore& store, uint32_t cell) {
  const std::unique_ptr<CellGeometry> geometry = CellGeometry::load(store.cellPath(cell), cell, store.materials().size());
  const Floor floor = findFloor(geometry->mesh(), geometry->bounds());
  if (!floor.found) return std::nullopt;
  return RoomFloor{floor.height, floor.area};
}

WorkPlaneGrid placeWorkPlaneGrid(const SceneStore& store, const WorkPlaneGridOptions& options) {
  const FloorLevels floors = findFloorLevels(store.cells());
  checkOptions(store, floors, options);
  WorkPlaneGrid grid;
  for (const CellInfo& info : store.cells()) {
    if (info.triangleCount == 0 || !chosen(info, floors.cellFloor[info.id], options)) continue;
    const std::unique_ptr<CellGeometry> cell =
        CellGeometry::load(store.cellPath(info.id), info.id, store.materials().size());
    const Floor floor = findFloor(cell->mesh(), cell->bounds());
    if (!floor.found) continue;
    std::vector<Vec3> points;
    const RoomGrid roomGrid(*cell, floor, options, indoorOpeningsAbove(store, info.id, floor.height + options.height));
    if (!roomGrid.place(points) || points.empty()) continue;
    WorkPlaneRoom room;
    room.cell = info.id;
    room.name = info.name;
    room.floor = floors.cellFloor[info.id];
    room.floorHeight = floor.height;
    room.floorArea = floor.area;
    room.sensors = uint32_t(points.size());
    grid.rooms.push_back(room);
    for (const Vec3& p : points) {
      Sensor sensor;
      sensor.position = p;
      sensor.direction = Vec3(0, 1, 0);
      sensor.cell = info.id;
      sensor.room = info.name;
      grid.sensors.push_back(std::move(sensor));
    }
  }
  return grid;
}

}  // namespace portico
