// The room finder's passes (room_cells.h): solid voxels, distances, cores,
// regions, boxes, portals. Flat arrays over the voxel grid, one byte or word
// per voxel each; every pass visits voxels in index order so the result
// depends on the input only.
#include "common/scene/import/room_cells.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

#include "common/accel/triangle_intersect.h"
#include "common/scene/import/binned_cells.h"
#include "common/triangle_box_overlap.h"

namespace portico {

namespace {

constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
constexpr uint16_t kFar = std::numeric_limits<uint16_t>::max();

struct Grid {
  std::array<uint32_t, 3> n{};
  uint64_t count() const { return uint64_t(n[0]) * n[1] * n[2]; }
  std::array<uint32_t, 3> coordinates(uint64_t i) const {
    return {uint32_t(i % n[0]), uint32_t((i / n[0]) % n[1]), uint32_t(i / (uint64_t(n[0]) * n[1]))};
  }
  uint64_t step(int axis) const { return axis == 0 ? 1 : (axis == 1 ? n[0] : uint64_t(n[0]) * n[1]); }
};

void report(const RoomFinderOptions& options, const char* stage, double fraction) {
  if (options.onProgress) options.onProgress(stage, fraction);
}

// Calls visit(v) for each voxel v triangle t of `object` touches (the voxel
// grown by a hair, so rounding only adds), unless skip(v) says it need not
// be tested.
template <typename Skip, typename Visit>
void forEachVoxelOfTriangle(const FoundRooms& rooms, const ImportedObject& object, size_t t, Skip&& skip,
                            Visit&& visit) {
  const float tolerance = 1e-3f * rooms.voxelSize;
  const Vec3 a = object.vertex(object.indices[3 * t]), b = object.vertex(object.indices[3 * t + 1]),
             c = object.vertex(object.indices[3 * t + 2]);
  const Vec3 lo = min(a, min(b, c)), hi = max(a, max(b, c));
  std::array<uint32_t, 3> first{}, last{};
  for (int axis = 0; axis < 3; ++axis)
    rooms.touchedVoxels(axis, lo[axis] - tolerance, hi[axis] + tolerance, first[axis], last[axis]);
  for (uint32_t z = first[2]; z <= last[2]; ++z)
    for (uint32_t y = first[1]; y <= last[1]; ++y)
      for (uint32_t x = first[0]; x <= last[0]; ++x) {
        const uint32_t v = rooms.voxelIndex(x, y, z);
        if (!skip(v) && triangleOverlapsBox(a, b, c, rooms.voxelBounds(x, y, z), tolerance)) visit(v);
      }
}

// Step 1: a voxel touched by a triangle (grown by a hair, so rounding only adds) is solid.
std::vector<uint8_t> solidVoxels(const ImportedScene& scene, const FoundRooms& rooms, const Grid& grid,
                                 const RoomFinderOptions& options) {
  std::vector<uint8_t> solid(grid.count(), 0);
  const uint64_t total = std::max<uint64_t>(1, scene.triangleCount());
  uint64_t done = 0;
  for (const ImportedObject& object : scene.objects)
    for (size_t t = 0; t < object.triangleCount(); ++t, ++done) {
      if (done % (1u << 20) == 0) report(options, "solid voxels", double(done) / double(total));
      forEachVoxelOfTriangle(
          rooms, object, t, [&](uint32_t v) { return solid[v] != 0; }, [&](uint32_t v) { solid[v] = 1; });
    }
  return solid;
}

// Step 2: chessboard distance (26 neighbours) of each voxel to the nearest solid one, in voxels.
std::vector<uint16_t> distanceToSolid(const std::vector<uint8_t>& solid, const Grid& grid) {
  std::vector<uint16_t> distance(grid.count(), kFar);
  std::vector<uint32_t> frontier, next;
  for (uint64_t v = 0; v < grid.count(); ++v)
    if (solid[v]) {
      distance[v] = 0;
      frontier.push_back(uint32_t(v));
    }
  for (uint16_t d = 1; !frontier.empty() && d < kFar; ++d) {
    next.clear();
    for (uint32_t v : frontier) {
      const auto c = grid.coordinates(v);
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int64_t x = int64_t(c[0]) + dx, y = int64_t(c[1]) + dy, z = int64_t(c[2]) + dz;
            if (x < 0 || y < 0 || z < 0 || x >= grid.n[0] || y >= grid.n[1] || z >= grid.n[2]) continue;
            const uint64_t u = uint64_t(x) + grid.n[0] * (uint64_t(y) + grid.n[1] * uint64_t(z));
            if (distance[u] != kFar) continue;
            distance[u] = d;
            next.push_back(uint32_t(u));
          }
    }
    std::swap(frontier, next);
  }
  return distance;
}

// Calls visit(u) for the face neighbours of v, in a fixed order.
template <typename Visit>
void forEachFaceNeighbour(const Grid& grid, uint64_t v, Visit&& visit) {
  const auto c = grid.coordinates(v);
  for (int axis = 0; axis < 3; ++axis) {
    if (c[axis] > 0) visit(v - grid.step(axis));
    if (c[axis] + 1 < grid.n[axis]) visit(v + grid.step(axis));
  }
}

// Breadth-first from every labelled voxel at once into unlabelled ones that `may` enter.
template <typename May>
void growLabels(const Grid& grid, std::vector<uint32_t>& label, May&& may) {
  std::vector<uint32_t> frontier, next;
  for (uint64_t v = 0; v < grid.count(); ++v)
    if (label[v] != kNone) frontier.push_back(uint32_t(v));
  while (!frontier.empty()) {
    next.clear();
    for (uint32_t v : frontier)
      forEachFaceNeighbour(grid, v, [&](uint64_t u) {
        if (label[u] != kNone || !may(u)) return;
        label[u] = label[v];
        next.push_back(uint32_t(u));
      });
    std::swap(frontier, next);
  }
}

// The face-connected component of `seed` among the voxels `member` accepts,
// by depth-first fill, marking each in `marked`.
template <typename Member>
std::vector<uint32_t> fillComponent(const Grid& grid, uint64_t seed, Member&& member, std::vector<uint8_t>& marked) {
  std::vector<uint32_t> members, stack{uint32_t(seed)};
  marked[seed] = 1;
  while (!stack.empty()) {
    const uint32_t v = stack.back();
    stack.pop_back();
    members.push_back(v);
    forEachFaceNeighbour(grid, v, [&](uint64_t u) {
      if (marked[u] || !member(u)) return;
      marked[u] = 1;
      stack.push_back(uint32_t(u));
    });
  }
  return members;
}

// Whether p lies inside a closed solid of the scene (meshes of closed
// solids whose faces look out, as IfcOpenShell tessellates IFC elements):
// along at least two of three skew directions (skew, so that no ray runs
// along a wall's edges; three, so that one ray through a glass pane or a
// gap does not decide), the first surface met faces away from p and the
// surfaces crossed are odd in number.
bool insideClosedSolid(const ImportedScene& scene, const Vec3& p) {
  const Vec3 directions[3] = {normalize(Vec3(1.0f, 0.0123f, 0.0371f)), normalize(Vec3(0.0291f, 1.0f, 0.0173f)),
                              normalize(Vec3(0.0137f, 0.0419f, 1.0f))};
  int inside = 0;
  for (const Vec3& direction : directions) {
    const Ray ray{p, direction};
    const WatertightRay frame(direction);
    uint64_t crossings = 0;
    float nearest = kInfinity;
    bool nearestFacesAway = false;
    for (const ImportedObject& object : scene.objects)
      for (size_t t = 0; t < object.triangleCount(); ++t) {
        const Vec3 a = object.vertex(object.indices[3 * t]), b = object.vertex(object.indices[3 * t + 1]),
                   c = object.vertex(object.indices[3 * t + 2]);
        float distance = 0, u = 0, v = 0;
        if (!intersectTriangle(frame, ray, a, b, c, distance, u, v)) continue;
        ++crossings;
        if (distance < nearest) {
          nearest = distance;
          nearestFacesAway = dot(cross(b - a, c - a), direction) > 0.0f;
        }
      }
    inside += int(crossings % 2 == 1 && nearestFacesAway);
  }
  return inside >= 2;
}

// Steps 3 and 4: each free voxel's region, 0 outdoors, kNone where no core
// reaches (solid voxels, the inside of thick walls); returns the number of
// rooms. A core inside a closed solid (a footing or a column thicker than
// an opening is wide: no triangle touches its inside) is no room, where
// `insideSolid` can tell.
template <typename InsideSolid>
uint32_t labelRegions(const std::vector<uint8_t>& solid, const std::vector<uint16_t>& distance, const Grid& grid,
                      uint16_t coreDistance, uint64_t minCoreVoxels, InsideSolid&& insideSolid,
                      std::vector<uint32_t>& region) {
  region.assign(grid.count(), kNone);
  std::vector<uint8_t> marked(grid.count(), 0);
  auto core = [&](uint64_t v) { return distance[v] >= coreDistance; };
  uint32_t rooms = 0;
  for (uint64_t seed = 0; seed < grid.count(); ++seed) {
    if (!core(seed) || marked[seed]) continue;
    // One core component; then kept as a room, as outdoors, or dropped.
    const std::vector<uint32_t> members = fillComponent(grid, seed, core, marked);
    bool touchesBoundary = false;
    for (uint32_t v : members) {
      const auto c = grid.coordinates(v);
      for (int axis = 0; axis < 3; ++axis)
        if (c[axis] == 0 || c[axis] + 1 == grid.n[axis]) touchesBoundary = true;
    }
    uint32_t id = kNone;
    if (touchesBoundary)
      id = 0;
    else if (members.size() >= minCoreVoxels && !insideSolid(members.front()))
      id = ++rooms;
    if (id == kNone) continue;
    for (uint32_t v : members) region[v] = id;
  }
  growLabels(grid, region, [&](uint64_t u) { return !solid[u]; });
  return rooms;
}

// A room's air, while `region` holds only free voxels reached from a core
// (rooms.rooms regions): counts, box, floor area, its deepest voxel's column,
// the clear square under its ceiling there, and evenly spread samples.
void describeRooms(const std::vector<uint32_t>& region, const std::vector<uint8_t>& solid,
                   const std::vector<uint16_t>& distance, const Grid& grid, FoundRooms& rooms) {
  struct Tally {
    uint64_t air = 0, floor = 0, deepest = 0;
    std::array<uint32_t, 3> lo{kNone, kNone, kNone}, hi{};
  };
  std::vector<Tally> tally(rooms.rooms + 1);
  for (uint64_t v = 0; v < grid.count(); ++v) {
    const uint32_t r = region[v];
    if (r == kNone || r == 0 || solid[v]) continue;
    Tally& t = tally[r];
    const auto c = grid.coordinates(v);
    if (t.air == 0 || distance[v] > distance[t.deepest]) t.deepest = v;
    ++t.air;
    if (c[1] > 0 && solid[v - grid.step(1)]) ++t.floor;
    for (int axis = 0; axis < 3; ++axis) {
      t.lo[axis] = std::min(t.lo[axis], c[axis]);
      t.hi[axis] = std::max(t.hi[axis], c[axis]);
    }
  }
  auto isAir = [&](uint64_t v, uint32_t r) { return region[v] == r && !solid[v]; };
  const float face = rooms.voxelSize * rooms.voxelSize;
  for (uint32_t r = 1; r <= rooms.rooms; ++r) {
    const Tally& t = tally[r];
    FoundRoom room;
    room.name = fmt::format("room {}", r);
    room.airVoxels = t.air;
    room.floorArea = double(t.floor) * face;
    room.air = Bounds3(Vec3(rooms.plane(0, t.lo[0]), rooms.plane(1, t.lo[1]), rooms.plane(2, t.lo[2])),
                       Vec3(rooms.plane(0, t.hi[0] + 1), rooms.plane(1, t.hi[1] + 1), rooms.plane(2, t.hi[2] + 1)));
    const auto c = grid.coordinates(t.deepest);
    uint32_t bottom = c[1], top = c[1];
    while (bottom > 0 && isAir(t.deepest - (c[1] - bottom + 1) * grid.step(1), r)) --bottom;
    while (top + 1 < grid.n[1] && isAir(t.deepest + (top + 1 - c[1]) * grid.step(1), r)) ++top;
    room.centre = Vec3(rooms.plane(0, c[0]) + 0.5f * rooms.voxelSize, rooms.plane(1, c[1]) + 0.5f * rooms.voxelSize,
                       rooms.plane(2, c[2]) + 0.5f * rooms.voxelSize);
    room.floor = rooms.plane(1, bottom);
    room.ceiling = rooms.plane(1, top + 1);
    // Grow a square ring by ring in the top layer while all of it is this room's air.
    uint32_t half = 0;
    for (;; ++half) {
      const int64_t h = half + 1;
      if (int64_t(c[0]) - h < 0 || int64_t(c[2]) - h < 0 || c[0] + h >= grid.n[0] || c[2] + h >= grid.n[2]) break;
      bool clear = true;
      for (int64_t dz = -h; dz <= h && clear; ++dz)
        for (int64_t dx = -h; dx <= h && clear; ++dx)
          if (std::max(std::abs(dx), std::abs(dz)) == h)
            clear = isAir(rooms.voxelIndex(uint32_t(c[0] + dx), top, uint32_t(c[2] + dz)), r);
      if (!clear) break;
    }
    room.clearHalfWidth = (float(half) + 0.5f) * rooms.voxelSize;
    rooms.roomAir.push_back(std::move(room));
  }
  // Every k-th air voxel of each room in index order: spread over the whole room.
  std::vector<uint64_t> seen(rooms.rooms + 1, 0);
  for (uint64_t v = 0; v < grid.count(); ++v) {
    const uint32_t r = region[v];
    if (r == kNone || r == 0 || solid[v]) continue;
    const uint64_t stride = (tally[r].air + kRoomSamples - 1) / kRoomSamples;
    if (seen[r]++ % stride != 0) continue;
    const auto c = grid.coordinates(v);
    rooms.roomAir[r - 1].samples.push_back(Vec3(rooms.plane(0, c[0]), rooms.plane(1, c[1]), rooms.plane(2, c[2])));
  }
}

// Step 5: boxes, each over the air of one region (its free voxels a core
// reached) and any voxels no region's air needs: solid ones and pockets no
// core reached. A box starts at the deepest air voxel not yet in a box, rooms
// before outdoors, so a room's first box starts in its middle; it grows by
// one layer on each face in turn, as long as the layer's voxels are free for
// it, so it spreads as the room does and stops where another region's air
// begins: a room with clear walls is one box, and it takes its walls, floor
// and ceiling (up to the next room's air), so rays meet them without
// crossing a portal. Rooms go first so that the building's envelope belongs
// to its rooms, where rays hit it, not to the outdoors. A box face never
// runs between two solid voxels unless a box met another there: a wall lying
// on a face would be hit on the far side of the portal, in the neighbour,
// from the wrong side (a thin wall split down its middle left 15 % of the
// light out). Returns each voxel's box.
std::vector<uint32_t> cutIntoBoxes(const std::vector<uint32_t>& air, const std::vector<uint32_t>& owner,
                                   const std::vector<uint16_t>& distance, uint16_t coreDistance, const Grid& grid,
                                   std::vector<std::array<uint32_t, 6>>& boxes, std::vector<uint32_t>& boxRegion) {
  std::vector<uint32_t> box(grid.count(), kNone);
  std::vector<uint8_t> undone;   // voxels of the small boxes undone (below)
  auto voxelAt = [&](uint32_t x, uint32_t y, uint32_t z) { return x + grid.n[0] * (uint64_t(y) + grid.n[1] * uint64_t(z)); };
  // How a box grows: over its region's air (more than half of each layer),
  // through walls (any voxel but another region's air), or through walls
  // and openings (also another region's air left by an undone small box).
  enum class Over { Air, Walls, Openings };
  // Whether every voxel of the box b is free for a box of region r growing `over`.
  auto fits = [&](const std::array<uint32_t, 6>& b, uint32_t r, Over over) {
    uint64_t own = 0, all = 0;
    for (uint32_t z = b[2]; z < b[5]; ++z)
      for (uint32_t y = b[1]; y < b[4]; ++y)
        for (uint32_t x = b[0]; x < b[3]; ++x, ++all) {
          const uint64_t v = voxelAt(x, y, z);
          if (box[v] != kNone) return false;
          if (air[v] != kNone && air[v] != r && !(over == Over::Openings && undone[v])) return false;
          own += air[v] == r;
        }
    return over != Over::Air || 2 * own > all;
  };
  auto grow = [&](uint32_t id, Over over) {
    std::array<uint32_t, 6>& b = boxes[id];
    std::array<bool, 6> open{true, true, true, true, true, true};
    while (std::find(open.begin(), open.end(), true) != open.end()) {
      for (int face = 0; face < 6; ++face) {
        if (!open[face]) continue;
        // A face stays shut once shut: its layer only widens, and what blocked it stays.
        const int axis = face / 2;
        const bool up = face % 2 == 1;
        std::array<uint32_t, 6> layer = b;
        if (up ? b[axis + 3] >= grid.n[axis] : b[axis] == 0) {
          open[face] = false;
          continue;
        }
        if (up)
          layer[axis] = b[axis + 3], layer[axis + 3] = b[axis + 3] + 1;
        else
          layer[axis + 3] = b[axis], layer[axis] = b[axis] - 1;
        if (!fits(layer, boxRegion[id], over)) {
          open[face] = false;
          continue;
        }
        for (uint32_t z = layer[2]; z < layer[5]; ++z)
          for (uint32_t y = layer[1]; y < layer[4]; ++y)
            for (uint32_t x = layer[0]; x < layer[3]; ++x) box[voxelAt(x, y, z)] = id;
        (up ? b[axis + 3] : b[axis]) = up ? b[axis + 3] + 1 : b[axis] - 1;
      }
    }
  };
  auto startBox = [&](uint64_t v, uint32_t r) {
    const auto c = grid.coordinates(v);
    const auto id = uint32_t(boxes.size());
    boxes.push_back({c[0], c[1], c[2], c[0] + 1, c[1] + 1, c[2] + 1});
    boxRegion.push_back(r);
    box[v] = id;
    return id;
  };
  // Air voxels in the order boxes start from them (rooms' air, deepest
  // first, then the outdoors', deepest first; each in index order): a
  // counting sort on that rank.
  uint16_t deepest = 0;
  for (uint64_t v = 0; v < grid.count(); ++v)
    if (air[v] != kNone) deepest = std::max(deepest, distance[v]);
  auto rank = [&](uint64_t v) { return size_t(air[v] == 0 ? deepest + 1 : 0) + (deepest - distance[v]); };
  std::vector<uint64_t> start(2 * (size_t(deepest) + 1) + 1, 0);
  for (uint64_t v = 0; v < grid.count(); ++v)
    if (air[v] != kNone) ++start[rank(v) + 1];
  for (size_t k = 1; k < start.size(); ++k) start[k] += start[k - 1];
  std::vector<uint32_t> order(start.back());
  for (uint64_t v = 0; v < grid.count(); ++v)
    if (air[v] != kNone) order[start[rank(v)]++] = uint32_t(v);
  for (uint32_t v : order)
    if (box[v] == kNone) {
      // First over the room's air (stopping at its walls, not at the first
      // doorway a face reaches), then on through its walls.
      const uint32_t id = startBox(v, air[v]);
      grow(id, Over::Air);
      grow(id, Over::Walls);
    }
  // Where two regions' fronts met at random (in a door or a window, the
  // border runs diagonally), and in a wall's cavity that some region's air
  // leaked into, the boxes above leave slivers. Small boxes and those two
  // voxels thin or less are undone, and the others grow on into their
  // voxels, as into a wall's: an opening's air goes to whichever room's box
  // reaches it first.
  const uint64_t smallBox = uint64_t(coreDistance) * coreDistance * coreDistance;
  undone.assign(grid.count(), 0);
  std::vector<uint32_t> kept(boxes.size(), kNone);
  std::vector<std::array<uint32_t, 6>> largeBoxes;
  std::vector<uint32_t> largeRegion;
  for (uint32_t id = 0; id < boxes.size(); ++id) {
    const auto& b = boxes[id];
    const uint32_t thinnest = std::min({b[3] - b[0], b[4] - b[1], b[5] - b[2]});
    if (uint64_t(b[3] - b[0]) * (b[4] - b[1]) * (b[5] - b[2]) < smallBox || thinnest <= 2) continue;
    kept[id] = uint32_t(largeBoxes.size());
    largeBoxes.push_back(b);
    largeRegion.push_back(boxRegion[id]);
  }
  for (uint64_t v = 0; v < grid.count(); ++v) {
    if (box[v] == kNone) continue;   // a wall's voxel no box took
    box[v] = kept[box[v]];
    undone[v] = box[v] == kNone;
  }
  boxes = std::move(largeBoxes);
  boxRegion = std::move(largeRegion);
  for (uint32_t id = 0; id < boxes.size(); ++id) grow(id, Over::Openings);
  // Voxels no large box could take (boxes met around them): boxes of their own.
  for (uint64_t v = 0; v < grid.count(); ++v)
    if (box[v] == kNone) grow(startBox(v, owner[v]), Over::Openings);
  return box;
}

// Outdoor air the building shelters: core voxels of the outdoors (region 0)
// with a solid voxel somewhere above and below them in their column, in
// components of at least minCoreVoxels (face neighbours). A room that lost
// a wall wider than an opening joins the outdoors, and is found here, over
// its floor and under its ceiling; so are a loggia and a covered balcony.
void describeShelteredAir(const std::vector<uint32_t>& region, const std::vector<uint8_t>& solid,
                          const std::vector<uint16_t>& distance, const Grid& grid, uint16_t coreDistance,
                          uint64_t minCoreVoxels, FoundRooms& rooms) {
  const uint64_t columns = uint64_t(grid.n[0]) * grid.n[2];
  std::vector<uint32_t> lowest(columns, kNone), highest(columns, 0);
  auto columnOf = [&](const std::array<uint32_t, 3>& c) { return c[0] + uint64_t(grid.n[0]) * c[2]; };
  for (uint64_t v = 0; v < grid.count(); ++v)
    if (solid[v]) {
      const auto c = grid.coordinates(v);
      const uint64_t column = columnOf(c);
      lowest[column] = std::min(lowest[column], c[1]);
      highest[column] = std::max(highest[column], c[1]);
    }
  auto sheltered = [&](uint64_t v) {
    if (region[v] != 0 || solid[v] || distance[v] < coreDistance) return false;
    const auto c = grid.coordinates(v);
    const uint64_t column = columnOf(c);
    return lowest[column] != kNone && lowest[column] < c[1] && c[1] < highest[column];
  };
  std::vector<uint8_t> marked(grid.count(), 0);
  for (uint64_t seed = 0; seed < grid.count(); ++seed) {
    if (marked[seed] || !sheltered(seed)) continue;
    std::vector<uint32_t> members = fillComponent(grid, seed, sheltered, marked);
    if (members.size() < minCoreVoxels) continue;
    std::sort(members.begin(), members.end());
    FoundRoom pocket;
    pocket.name = fmt::format("sheltered {}", rooms.shelteredAir.size() + 1);
    pocket.airVoxels = members.size();
    const uint64_t stride = (members.size() + kRoomSamples - 1) / kRoomSamples;
    for (size_t k = 0; k < members.size(); ++k) {
      const auto c = grid.coordinates(members[k]);
      const Vec3 corner(rooms.plane(0, c[0]), rooms.plane(1, c[1]), rooms.plane(2, c[2]));
      pocket.air.extend(corner);
      pocket.air.extend(corner + Vec3(rooms.voxelSize));
      if (k % stride == 0) pocket.samples.push_back(corner);
    }
    rooms.shelteredAir.push_back(std::move(pocket));
  }
}

}  // namespace

void FoundRooms::touchedVoxels(int axis, float lo, float hi, uint32_t& first, uint32_t& last) const {
  const float f = std::floor((lo - origin[axis]) / voxelSize), l = std::floor((hi - origin[axis]) / voxelSize);
  const float top = float(voxels[axis] - 1);
  first = uint32_t(std::clamp(f, 0.0f, top));
  last = uint32_t(std::clamp(l, float(first), top));
}

Bounds3 FoundRooms::voxelBounds(uint32_t x, uint32_t y, uint32_t z) const {
  return Bounds3(Vec3(plane(0, x), plane(1, y), plane(2, z)), Vec3(plane(0, x + 1), plane(1, y + 1), plane(2, z + 1)));
}

FoundRooms findRooms(const ImportedScene& scene, const std::string& source, const RoomFinderOptions& options) {
  auto noRooms = [&](const std::string& why) {
    return std::runtime_error(fmt::format("no rooms found in {}: {}; use --grid N for uniform cells instead", source, why));
  };
  if (scene.bounds.empty() || !isFinite(scene.bounds.lo) || !isFinite(scene.bounds.hi))
    throw noRooms("it has no geometry");
  FoundRooms rooms;
  // Open air around the building, wider than a core needs, so outdoors is one region all round.
  const float padding = options.openingWidth;
  const Vec3 lo = scene.bounds.lo - Vec3(padding), extent = scene.bounds.diagonal() + Vec3(2 * padding);
  rooms.voxelSize = options.voxelSize;
  for (;;) {
    for (int axis = 0; axis < 3; ++axis)
      rooms.voxels[axis] = uint32_t(std::ceil(extent[axis] / rooms.voxelSize));
    const double count = double(rooms.voxels[0]) * rooms.voxels[1] * rooms.voxels[2];
    if (count <= double(options.maxVoxels)) break;
    rooms.voxelSize *= float(std::cbrt(count / double(options.maxVoxels))) * 1.01f;
  }
  rooms.origin = lo;
  const Grid grid{rooms.voxels};
  const auto coreDistance = uint16_t(std::floor(0.5f * options.openingWidth / rooms.voxelSize) + 1);
  if (coreDistance < 2)
    throw noRooms(fmt::format("the building is too large for {} voxels of {} m", options.maxVoxels, rooms.voxelSize));
  const auto minCoreVoxels =
      uint64_t(std::ceil(options.minRoomVolume / (rooms.voxelSize * rooms.voxelSize * rooms.voxelSize)));

  report(options, "solid voxels", 0.0);
  const std::vector<uint8_t> solid = solidVoxels(scene, rooms, grid, options);
  report(options, "distances", 0.0);
  const std::vector<uint16_t> distance = distanceToSolid(solid, grid);
  report(options, "regions", 0.0);
  std::vector<uint32_t> region;
  auto insideSolid = [&](uint32_t v) {
    if (!options.solidsAreClosed) return false;
    const auto c = grid.coordinates(v);
    return insideClosedSolid(scene, rooms.voxelBounds(c[0], c[1], c[2]).center());
  };
  rooms.rooms = labelRegions(solid, distance, grid, coreDistance, minCoreVoxels, insideSolid, region);
  if (rooms.rooms == 0)
    throw noRooms(fmt::format("no enclosed space wider than {} m (the free space is all outdoors at {} m voxels)",
                              options.openingWidth, rooms.voxelSize));
  describeRooms(region, solid, distance, grid, rooms);
  describeShelteredAir(region, solid, distance, grid, coreDistance, minCoreVoxels, rooms);
  // Each region's air: its free voxels a core reached (kNone elsewhere).
  const std::vector<uint32_t> air = region;
  // Solid voxels and pockets no core reached (inside thick walls) join the region beside them.
  growLabels(grid, region, [](uint64_t) { return true; });

  report(options, "boxes", 0.0);
  std::vector<std::array<uint32_t, 6>> boxes;
  std::vector<uint32_t> boxRegion;
  rooms.voxelCell = cutIntoBoxes(air, region, distance, coreDistance, grid, boxes, boxRegion);
  std::vector<uint32_t> boxesInRegion(rooms.rooms + 1, 0);
  for (size_t k = 0; k < boxes.size(); ++k) {
    const auto& b = boxes[k];
    const uint32_t r = boxRegion[k];
    ImportedCell cell;
    cell.name = r == 0 ? fmt::format("outdoors-{}", boxesInRegion[0]) : fmt::format("room-{}-{}", r, boxesInRegion[r]);
    ++boxesInRegion[r];
    cell.bounds = Bounds3(Vec3(rooms.plane(0, b[0]), rooms.plane(1, b[1]), rooms.plane(2, b[2])),
                          Vec3(rooms.plane(0, b[3]), rooms.plane(1, b[4]), rooms.plane(2, b[5])));
    rooms.cells.push_back(cell);
    rooms.cellRegion.push_back(r);
  }

  // Portals: per pair of boxes, the whole face they share.
  report(options, "portals", 0.0);
  struct Face {
    int axis;
    uint32_t plane;
    std::array<uint32_t, 2> lo, hi;   // voxel range on the two other axes, inclusive
  };
  std::map<std::pair<uint32_t, uint32_t>, Face> faces;
  for (uint64_t v = 0; v < grid.count(); ++v) {
    const auto c = grid.coordinates(v);
    for (int axis = 0; axis < 3; ++axis) {
      if (c[axis] + 1 >= grid.n[axis]) continue;
      const uint64_t u = v + grid.step(axis);
      const uint32_t a = rooms.voxelCell[v], b = rooms.voxelCell[u];
      if (a == b) continue;
      const int s = (axis + 1) % 3, t = (axis + 2) % 3;
      auto [it, inserted] = faces.try_emplace({std::min(a, b), std::max(a, b)},
                                              Face{axis, c[axis] + 1, {c[s], c[t]}, {c[s], c[t]}});
      Face& face = it->second;
      face.lo = {std::min(face.lo[0], c[s]), std::min(face.lo[1], c[t])};
      face.hi = {std::max(face.hi[0], c[s]), std::max(face.hi[1], c[t])};
    }
  }
  for (const auto& [pair, face] : faces) {
    const int s = (face.axis + 1) % 3, t = (face.axis + 2) % 3;
    auto corner = [&](uint32_t i, uint32_t j) {
      Vec3 p;
      p[face.axis] = rooms.plane(face.axis, face.plane);
      p[s] = rooms.plane(s, i);
      p[t] = rooms.plane(t, j);
      return p;
    };
    rooms.portals.push_back(ImportedPortal{pair.first, pair.second,
                                           {corner(face.lo[0], face.lo[1]), corner(face.hi[0] + 1, face.lo[1]),
                                            corner(face.hi[0] + 1, face.hi[1] + 1), corner(face.lo[0], face.hi[1] + 1)}});
  }
  return rooms;
}

namespace {

uint32_t cellHolding(const FoundRooms& rooms, const Vec3& p) {
  std::array<uint32_t, 3> c{};
  for (int axis = 0; axis < 3; ++axis) rooms.touchedVoxels(axis, p[axis], p[axis], c[axis], c[axis]);
  return rooms.voxelCell[rooms.voxelIndex(c[0], c[1], c[2])];
}

// The axis a light's edge runs along, or -1 when oblique.
int edgeAxis(const Vec3& edge) {
  int axis = 0;
  for (int a = 1; a < 3; ++a)
    if (std::abs(edge[a]) > std::abs(edge[axis])) axis = a;
  for (int a = 0; a < 3; ++a)
    if (a != axis && std::abs(edge[a]) > 1e-6f * std::abs(edge[axis])) return -1;
  return std::abs(edge[axis]) > 0.0f ? axis : -1;
}

std::vector<AreaLight> roomLights(const ImportedLight& light, const FoundRooms& rooms) {
  AreaLight whole = light.areaLight();
  const int axis1 = edgeAxis(light.shape.edge1), axis2 = edgeAxis(light.shape.edge2);
  const Vec3 nudge = light.kind == LightShape::Point ? Vec3(0.0f) : whole.normal() * (1e-3f * rooms.voxelSize);
  if (light.kind != LightShape::Parallelogram || axis1 < 0 || axis2 < 0 || axis1 == axis2) {
    whole.cell = cellHolding(rooms, whole.center() + nudge);
    return {whole};
  }
  const int normalAxis = 3 - axis1 - axis2;
  const float planeValue = whole.corner[normalAxis] + nudge[normalAxis];
  Bounds3 extent;
  Vec3 corners[4];
  for (int k = 0, n = whole.corners(corners); k < n; ++k) extent.extend(corners[k]);
  std::vector<AreaLight> pieces;
  for (uint32_t id = 0; id < rooms.cells.size(); ++id) {
    const Bounds3& box = rooms.cells[id].bounds;
    if (!(planeValue >= box.lo[normalAxis] && planeValue < box.hi[normalAxis])) continue;
    const float lo1 = std::max(extent.lo[axis1], box.lo[axis1]), hi1 = std::min(extent.hi[axis1], box.hi[axis1]);
    const float lo2 = std::max(extent.lo[axis2], box.lo[axis2]), hi2 = std::min(extent.hi[axis2], box.hi[axis2]);
    if (!(lo1 < hi1 && lo2 < hi2)) continue;
    // The piece keeps the whole light's orientation (edge signs), so it emits the same way.
    AreaLight piece = whole;
    piece.cell = id;
    const bool flip1 = light.shape.edge1[axis1] < 0, flip2 = light.shape.edge2[axis2] < 0;
    piece.corner[axis1] = flip1 ? hi1 : lo1;
    piece.corner[axis2] = flip2 ? hi2 : lo2;
    piece.edge1 = Vec3(0.0f);
    piece.edge1[axis1] = flip1 ? lo1 - hi1 : hi1 - lo1;
    piece.edge2 = Vec3(0.0f);
    piece.edge2[axis2] = flip2 ? lo2 - hi2 : hi2 - lo2;
    pieces.push_back(piece);
  }
  return pieces;
}

}  // namespace

void writeRoomCells(const ImportedScene& scene, const FoundRooms& rooms, SceneStoreWriter& writer) {
  for (const ImportedPortal& portal : rooms.portals) writer.addPortal(portal.cellA, portal.cellB, portal.polygon);
  for (const ImportedLight& light : scene.lights)
    for (const AreaLight& piece : roomLights(light, rooms)) writer.addLight(piece);
  for (size_t k = 0; k < scene.cameras.size(); ++k) {
    Camera camera = scene.cameras[k];
    camera.cell = cellHolding(rooms, camera.origin);
    if (k == 0)
      writer.setCamera(camera);
    else
      writer.addCamera(camera);
  }
  std::vector<uint32_t> touched;
  writeBinnedCells(
      scene, uint32_t(rooms.cells.size()),
      [&](const ImportedObject& object, size_t t, const std::function<void(uint32_t)>& visit) {
        touched.clear();
        auto known = [&](uint32_t v) {
          return std::find(touched.begin(), touched.end(), rooms.voxelCell[v]) != touched.end();
        };
        forEachVoxelOfTriangle(rooms, object, t, known, [&](uint32_t v) { touched.push_back(rooms.voxelCell[v]); });
        std::sort(touched.begin(), touched.end());
        for (uint32_t cell : touched) visit(cell);
      },
      [&](uint32_t id) { return rooms.cells[id].name; }, [&](uint32_t id) { return rooms.cells[id].bounds; },
      writer);
}

}  // namespace portico
