#include "common/scene/generator/building_generator.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <numeric>
#include <optional>
#include <stdexcept>

#include "common/rng.h"
#include "common/scene/generator/demo_furniture.h"
#include "common/scene/generator/material_palette.h"
#include "common/scene/generator/mesh_builder.h"
#include "common/scene/generator/standing_camera.h"
#include "common/scene/store/scene_store.h"
#include "common/util/apportion.h"

namespace portico {

namespace {

using furniture::FloorRect;
using demo::DemoRandom;

constexpr float kStorey = 3.0f;          // floor to floor
constexpr float kCeiling = 2.8f;         // above the cell's floor; the plenum above closes the cell
constexpr float kDoorWidth = 0.9f, kDoorHeight = 2.1f;
constexpr float kWindowSill = 0.9f, kWindowTop = 2.2f;
constexpr float kFacadeDepth = 1.0f;     // the strip of outside air along a wing
constexpr float kOpeningHeight = 2.5f;   // corridor ends into junctions
constexpr float kStairWidth = 1.2f, kStairOpening = 3.0f, kStairRun = 3.0f;
constexpr float kSkyHeight = 60.0f;

enum class CellKind : uint8_t { Room, Corridor, Junction, Facade, Sky };

// A wing or junction's frame: world = origin + along * u + across * v + y.
struct Frame {
  Vec3 origin, along, across;
  Vec3 at(float u, float v, float y = 0.0f) const { return origin + along * u + across * v + Vec3(0, y, 0); }
  FloorRect rect(float u0, float u1, float v0, float v1) const {
    const Vec3 a = at(u0, v0), b = at(u1, v1);
    return FloorRect{std::min(a.x, b.x), std::max(a.x, b.x), std::min(a.z, b.z), std::max(a.z, b.z)};
  }
  // A vertical rectangle in the plane v = const (u from u0 to u1) or u = const.
  std::vector<Vec3> wallAtV(float v, float u0, float u1, float y0, float y1) const {
    return {at(u0, v, y0), at(u1, v, y0), at(u1, v, y1), at(u0, v, y1)};
  }
  std::vector<Vec3> wallAtU(float u, float v0, float v1, float y0, float y1) const {
    return {at(u, v0, y0), at(u, v1, y0), at(u, v1, y1), at(u, v0, y1)};
  }
};

Vec3 acrossOf(const Vec3& along) { return cross(along, Vec3(0, 1, 0)); }

struct StairPlan {
  FloorRect opening;   // in the ceiling, and the portal to the junction above
  std::vector<Bounds3> steps;   // relative to the floor (y from 0)
};

// One cell of the floor plan, at floor 0; floors repeat it kStorey higher.
struct TemplateCell {
  CellKind kind = CellKind::Room;
  std::string name;
  FloorRect rect;
  std::vector<FloorRect> keepOut;   // furniture-free floor (door fronts, stairs)
  FloorRect lightArea;              // where ceiling lights may go
  StairPlan stair;                  // junctions only
  float weight = 1.0f;              // share of the room triangle budget
  // Where a standing camera is put (rooms: just inside the door, where no
  // furniture stands; corridors: at one end) and where it looks (the far
  // wall's middle; the corridor's other end), at floor 0.
  Vec3 viewFrom, viewTo;
};

struct TemplatePortal {
  size_t a = 0, b = 0;              // template cell indices
  std::vector<Vec3> polygon;        // at floor 0
};

struct Window {
  size_t room = 0, facade = 0;      // template cell index, facade index
  std::vector<Vec3> polygon;
};

struct FloorTemplate {
  std::vector<TemplateCell> cells;
  std::vector<TemplatePortal> portals;
  std::vector<size_t> junctions;
  std::vector<Window> windows;
  std::vector<FloorRect> facades;   // strips of outside air, one per wing side
};

struct PathElement {
  bool junction = false;
  Vec3 in, out;         // junction: direction of arrival and of departure
  Vec3 direction;       // wing: direction it runs
};

std::vector<PathElement> layoutPath(BuildingLayout layout) {
  const Vec3 px(1, 0, 0), nx(-1, 0, 0), pz(0, 0, 1), nz(0, 0, -1);
  const auto wing = [](Vec3 d) { return PathElement{false, {}, {}, d}; };
  const auto junction = [](Vec3 in, Vec3 out) { return PathElement{true, in, out, {}}; };
  switch (layout) {
    case BuildingLayout::Bar: return {wing(px), junction(px, px), wing(px)};
    case BuildingLayout::LShape: return {wing(px), junction(px, pz), wing(pz)};
    case BuildingLayout::ZShape: return {wing(px), junction(px, pz), wing(pz), junction(pz, px), wing(px)};
    case BuildingLayout::Ring:
      return {junction(nz, px), wing(px), junction(px, pz), wing(pz), junction(pz, nx), wing(nx), junction(nx, nz),
              wing(nz)};
  }
  return {};
}

// Room widths along one side of a wing, scaled to sum to `length`.
std::vector<float> sideWidths(uint32_t rooms, float length, const BuildingPreset& preset, DemoRandom& random) {
  std::vector<float> widths(rooms);
  for (float& w : widths) w = random.uniform(preset.minRoomWidth, preset.maxRoomWidth);
  const float sum = std::accumulate(widths.begin(), widths.end(), 0.0f);
  for (float& w : widths) w *= length / sum;
  return widths;
}

class FloorPlanner {
 public:
  FloorPlanner(const BuildingPreset& preset, DemoRandom& random) : preset_(preset), random_(random) {
    c_ = preset.corridorHalfWidth;
    halfWidth_ = c_ + preset.roomDepth;
  }

  FloorTemplate plan(const std::vector<uint32_t>& roomsPerWing) {
    const std::vector<PathElement> path = layoutPath(preset_.layout);
    // Wing lengths: each from its own rooms, or one for all in a ring (it closes).
    std::vector<float> lengths;
    for (uint32_t rooms : roomsPerWing) {
      const uint32_t longSide = (rooms + 1) / 2;
      lengths.push_back(float(longSide) * 0.5f * (preset_.minRoomWidth + preset_.maxRoomWidth));
    }
    if (preset_.layout == BuildingLayout::Ring) {
      const float longest = *std::max_element(lengths.begin(), lengths.end());
      std::fill(lengths.begin(), lengths.end(), longest);
    }
    Vec3 cursor(0.0f), direction = path.front().junction ? path.front().in : path.front().direction;
    size_t wing = 0;
    std::optional<size_t> openCorridor;   // a corridor whose far end waits for a junction
    std::optional<size_t> firstJunction;
    for (const PathElement& element : path) {
      if (element.junction) {
        const size_t junction = addJunction(cursor, element, openCorridor);
        if (!firstJunction) firstJunction = junction;
        direction = element.out;
        cursor = cursor + element.in * halfWidth_ + element.out * halfWidth_;
      } else {
        openCorridor = addWing(cursor, element.direction, lengths[wing], roomsPerWing[wing], wing);
        cursor = cursor + element.direction * lengths[wing];
        ++wing;
      }
    }
    // A ring's last wing ends at its first junction.
    if (preset_.layout == BuildingLayout::Ring && openCorridor && firstJunction)
      joinCorridorEnd(*openCorridor, *firstJunction, cursor, direction);
    for (size_t j : floor_.junctions) planStair(j);
    return std::move(floor_);
  }

 private:
  size_t addCell(CellKind kind, std::string name, const FloorRect& rect) {
    TemplateCell cell;
    cell.kind = kind;
    cell.name = std::move(name);
    cell.rect = rect;
    cell.lightArea = rect;
    floor_.cells.push_back(std::move(cell));
    return floor_.cells.size() - 1;
  }

  // The corridor's end at `point` (travelling `direction`) opens into `junction`.
  void joinCorridorEnd(size_t corridor, size_t junction, const Vec3& point, const Vec3& direction) {
    const Frame end{point, direction, acrossOf(direction)};
    floor_.portals.push_back({corridor, junction, end.wallAtU(0.0f, -c_ + 0.05f, c_ - 0.05f, 0.0f, kOpeningHeight)});
    usedFaces_[junction].push_back(direction * -1.0f);
  }

  size_t addJunction(const Vec3& entry, const PathElement& element, std::optional<size_t> arrivingCorridor) {
    const Frame frame{entry, element.in, acrossOf(element.in)};
    const size_t j = addCell(CellKind::Junction, fmt::format("junction-{}", floor_.junctions.size()),
                             frame.rect(0.0f, 2.0f * halfWidth_, -halfWidth_, halfWidth_));
    floor_.junctions.push_back(j);
    if (arrivingCorridor) joinCorridorEnd(*arrivingCorridor, j, entry, element.in);
    pendingExit_ = j;
    usedFaces_[j].push_back(element.out);
    return j;
  }

  // Returns the corridor's template index.
  size_t addWing(const Vec3& start, const Vec3& direction, float length, uint32_t rooms, size_t wing) {
    const Frame frame{start, direction, acrossOf(direction)};
    const size_t corridor = addCell(CellKind::Corridor, fmt::format("corridor-{}", wing),
                                    frame.rect(0.0f, length, -c_, c_));
    floor_.cells[corridor].viewFrom = frame.at(0.5f, 0.0f);
    floor_.cells[corridor].viewTo = frame.at(length, 0.0f);
    if (pendingExit_) {   // the junction we leave opens into this corridor
      floor_.portals.push_back({*pendingExit_, corridor, frame.wallAtU(0.0f, -c_ + 0.05f, c_ - 0.05f, 0.0f, kOpeningHeight)});
      pendingExit_.reset();
    }
    const uint32_t sideRooms[2] = {(rooms + 1) / 2, rooms / 2};
    for (int side = 0; side < 2; ++side) {
      if (sideRooms[side] == 0) continue;
      const float sign = side == 0 ? 1.0f : -1.0f;
      const size_t facade = floor_.facades.size();
      // The facade strip stops kFacadeDepth short of each end, so strips of
      // wings meeting at an inside corner never overlap.
      floor_.facades.push_back(side == 0 ? frame.rect(kFacadeDepth, length - kFacadeDepth, halfWidth_, halfWidth_ + kFacadeDepth)
                                         : frame.rect(kFacadeDepth, length - kFacadeDepth, -halfWidth_ - kFacadeDepth, -halfWidth_));
      float u = 0.0f;
      const std::vector<float> widths = sideWidths(sideRooms[side], length, preset_, random_);
      for (uint32_t k = 0; k < sideRooms[side]; ++k) {
        const float u0 = u, u1 = (k + 1 == sideRooms[side]) ? length : u + widths[k];
        u = u1;
        const float v0 = side == 0 ? c_ : -halfWidth_, v1 = side == 0 ? halfWidth_ : -c_;
        const size_t room = addCell(CellKind::Room, fmt::format("room-{}{}{}", wing, side == 0 ? 'a' : 'b', k),
                                    frame.rect(u0, u1, v0, v1));
        const float doorU = preset_.style == furniture::Style::Regular
                                ? 0.5f * (u0 + u1 - kDoorWidth)
                                : random_.centimetres(u0 + 0.4f, u1 - 0.4f - kDoorWidth);
        floor_.portals.push_back({corridor, room, frame.wallAtV(sign * c_, doorU, doorU + kDoorWidth, 0.0f, kDoorHeight)});
        floor_.cells[room].keepOut.push_back(frame.rect(doorU - 0.3f, doorU + kDoorWidth + 0.3f, sign * c_, sign * (c_ + 1.3f)));
        floor_.cells[room].viewFrom = frame.at(doorU + 0.5f * kDoorWidth, sign * (c_ + 0.6f));
        floor_.cells[room].viewTo = frame.at(0.5f * (u0 + u1), sign * halfWidth_);
        // A window centred in the outer wall, kept within the facade strip.
        const float w0 = std::max(u0 + 0.5f, kFacadeDepth + 0.1f), w1 = std::min(u1 - 0.5f, length - kFacadeDepth - 0.1f);
        const float mid = 0.5f * (w0 + w1), half = std::min(1.0f, 0.5f * (w1 - w0));
        if (half >= 0.3f)
          floor_.windows.push_back({room, facade, frame.wallAtV(sign * halfWidth_, mid - half, mid + half, kWindowSill, kWindowTop)});
        const float area = (u1 - u0) * preset_.roomDepth;
        floor_.cells[room].weight =
            area * (preset_.style == furniture::Style::HandMade ? random_.uniform(0.15f, 1.85f) : 1.0f);
      }
    }
    return corridor;
  }

  // The stairs run along a wall of the junction that no corridor opens in.
  void planStair(size_t j) {
    TemplateCell& cell = floor_.cells[j];
    const Vec3 faces[4] = {Vec3(-1, 0, 0), Vec3(1, 0, 0), Vec3(0, 0, -1), Vec3(0, 0, 1)};
    Vec3 wall = faces[0];
    for (const Vec3& face : faces) {
      bool used = false;
      for (const Vec3& u : usedFaces_[j]) used |= dot(u, face) > 0.5f;
      if (!used) { wall = face; break; }
    }
    // Frame: u along the wall from its low end, v inward from the wall.
    const FloorRect& r = cell.rect;
    Frame frame;
    if (wall.x != 0) {
      frame.origin = Vec3(wall.x < 0 ? r.x0 : r.x1, 0, r.z0);
      frame.along = Vec3(0, 0, 1);
      frame.across = Vec3(-wall.x, 0, 0);
    } else {
      frame.origin = Vec3(r.x0, 0, wall.z < 0 ? r.z0 : r.z1);
      frame.along = Vec3(1, 0, 0);
      frame.across = Vec3(0, 0, -wall.z);
    }
    const float v0 = 0.2f, v1 = v0 + kStairWidth, open0 = 0.4f, open1 = open0 + kStairOpening;
    cell.stair.opening = frame.rect(open0, open1, v0, v1);
    const int steps = 14;
    const float run = kStairRun / float(steps), rise = kCeiling / float(steps + 1);
    for (int s = 0; s < steps; ++s) {   // rising toward the opening
      const float uA = open1 + kStairRun - float(s + 1) * run, uB = open1 + kStairRun - float(s) * run;
      const FloorRect f = frame.rect(uA, uB, v0, v1);
      cell.stair.steps.push_back(Bounds3(Vec3(f.x0, 0, f.z0), Vec3(f.x1, rise * float(s + 1), f.z1)));
    }
    cell.keepOut.push_back(frame.rect(0.0f, open1 + kStairRun + 1.0f, 0.0f, v1 + 1.0f));
    // Lights keep away from the stair's side of the hall.
    const FloorRect clear = frame.rect(0.0f, 0.0f, v1 + 1.0f, v1 + 1.0f);
    cell.lightArea = cell.rect;
    if (frame.across.x > 0) cell.lightArea.x0 = clear.x0;
    if (frame.across.x < 0) cell.lightArea.x1 = clear.x1;
    if (frame.across.z > 0) cell.lightArea.z0 = clear.z0;
    if (frame.across.z < 0) cell.lightArea.z1 = clear.z1;
  }

  const BuildingPreset& preset_;
  DemoRandom& random_;
  float c_ = 1.0f, halfWidth_ = 6.0f;
  FloorTemplate floor_;
  std::optional<size_t> pendingExit_;
  std::map<size_t, std::vector<Vec3>> usedFaces_;
};

// ---- the whole building --------------------------------------------------

struct PlannedCell {
  CellKind kind = CellKind::Room;
  std::string name;
  Bounds3 box;
  const TemplateCell* source = nullptr;   // null for facades and the sky
  uint32_t floor = 0;
  std::vector<uint32_t> portals;          // ids of portals touching it
  std::vector<AreaLight> lights;
  std::vector<uint32_t> lightMaterials;   // one per light
  bool stairUp = false, stairDown = false;
};

struct FurnitureMaterials {
  uint32_t wall, roomFloor, corridorFloor, ceiling, light, stair;
  furniture::Materials pieces;
};

FurnitureMaterials addMaterials(SceneStoreWriter& writer) {
  FurnitureMaterials m{};
  m.wall = palette::add(writer, palette::kWallWhite);
  m.roomFloor = palette::add(writer, palette::kFloorWood);
  m.corridorFloor = palette::add(writer, palette::kFloorTiles);
  m.ceiling = palette::add(writer, palette::kCeiling);
  m.light = palette::add(writer, palette::kLight);
  m.stair = palette::add(writer, palette::kConcrete);
  furniture::Materials& p = m.pieces;
  p.wood = palette::add(writer, palette::kWood);
  p.darkWood = palette::add(writer, palette::kDarkWood);
  p.metal = palette::add(writer, palette::kMetalGrey);
  p.white = palette::add(writer, palette::kLaminateWhite);
  p.screen = palette::add(writer, palette::kScreen);
  for (int k = 0; k < 3; ++k) p.fabrics[k] = palette::add(writer, palette::kFabrics[k]);
  for (int k = 0; k < 3; ++k) p.books[k] = palette::add(writer, palette::kBooks[k]);
  p.leaf = palette::add(writer, palette::kLeaf);
  p.pot = palette::add(writer, palette::kTerracotta);
  return m;
}

float area(const FloorRect& r) { return (r.x1 - r.x0) * (r.z1 - r.z0); }

// n flush ceiling panels in a near-square grid over `r`, facing down.
std::vector<AreaLight> lightGrid(const FloorRect& r, float ceilingY, uint32_t n, uint32_t cell) {
  std::vector<AreaLight> lights;
  if (n == 0) return lights;
  const float wx = r.x1 - r.x0, wz = r.z1 - r.z0;
  const uint32_t nx = std::max(1u, uint32_t(std::lround(std::sqrt(double(n) * wx / wz))));
  const uint32_t nz = (n + nx - 1) / nx;
  const float size = std::min(0.6f, 0.5f * std::min(wx / float(nx), wz / float(nz)));
  for (uint32_t k = 0; k < n; ++k) {
    const float cx = r.x0 + wx * (float(k % nx) + 0.5f) / float(nx);
    const float cz = r.z0 + wz * (float(k / nx) + 0.5f) / float(nz);
    AreaLight light;
    light.cell = cell;
    light.corner = Vec3(cx - 0.5f * size, ceilingY - 0.001f, cz - 0.5f * size);
    light.edge1 = Vec3(size, 0, 0);   // cross(x, z) = -y: facing down
    light.edge2 = Vec3(0, 0, size);
    lights.push_back(light);   // its radiance: PanelMaterials
  }
  return lights;
}

// Which face of `box` a portal lies on, and its rectangle there in
// MeshBuilder's in-plane coordinates; nullopt for a portal covering the
// whole top face (to the sky: no hole, the ceiling below stays whole).
struct FaceHole {
  int axis = 0;
  bool high = false;
  PlaneRect rect;
};
std::optional<FaceHole> holeOf(const Bounds3& box, const std::vector<Vec3>& polygon) {
  Bounds3 p;
  for (const Vec3& v : polygon) p.extend(v);
  for (int axis = 0; axis < 3; ++axis) {
    if (p.hi[axis] - p.lo[axis] > 1e-4f) continue;
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    FaceHole hole{axis, std::abs(p.lo[axis] - box.hi[axis]) < 1e-3f, PlaneRect{p.lo[u], p.hi[u], p.lo[v], p.hi[v]}};
    if (axis == 1 && hole.high && p.lo.x <= box.lo.x + 1e-3f && p.hi.x >= box.hi.x - 1e-3f &&
        p.lo.z <= box.lo.z + 1e-3f && p.hi.z >= box.hi.z - 1e-3f)
      return std::nullopt;
    return hole;
  }
  return std::nullopt;
}

// The building's plan as it is written: every cell, and the portals' polygons.
struct BuildingPlan {
  std::vector<PlannedCell> cells;   // floor after floor, then the facades, then the sky
  std::vector<std::vector<Vec3>> portalPolygons;   // by portal id
  size_t floorCells = 0;            // cells of one floor
  size_t firstFacade = 0;
  uint32_t skyId = 0;
  float top = 0;                    // the roof's height
};

// Rooms per wing: cells = floors * (wings + junctions + rooms) + 2 facades
// per wing + sky, shared as evenly as the wings allow.
std::vector<uint32_t> roomsPerWing(const BuildingPreset& preset) {
  const std::vector<PathElement> path = layoutPath(preset.layout);
  const uint32_t wings = uint32_t(std::count_if(path.begin(), path.end(), [](auto& e) { return !e.junction; }));
  const uint32_t junctions = uint32_t(path.size()) - wings;
  const double perFloor = double(preset.cells - 2 * wings - 1) / double(preset.floors);
  const uint32_t roomsPerFloor = uint32_t(std::max<long>(2 * wings, std::lround(perFloor) - long(wings + junctions)));
  std::vector<uint32_t> rooms(wings, roomsPerFloor / wings);
  for (uint32_t w = 0; w < roomsPerFloor % wings; ++w) ++rooms[w];
  return rooms;
}

// The cells of every floor, then the facades (the sky comes with the camera).
void planCells(const BuildingPreset& preset, const FloorTemplate& floor, BuildingPlan& plan) {
  plan.top = kStorey * float(preset.floors);
  for (uint32_t f = 0; f < preset.floors; ++f)
    for (const TemplateCell& t : floor.cells) {
      PlannedCell cell;
      cell.kind = t.kind;
      cell.name = fmt::format("f{}-{}", f, t.name);
      cell.box = Bounds3(Vec3(t.rect.x0, kStorey * float(f), t.rect.z0), Vec3(t.rect.x1, kStorey * float(f + 1), t.rect.z1));
      cell.source = &t;
      cell.floor = f;
      cell.stairUp = t.kind == CellKind::Junction && f + 1 < preset.floors;
      cell.stairDown = t.kind == CellKind::Junction && f > 0;
      plan.cells.push_back(std::move(cell));
    }
  plan.firstFacade = plan.cells.size();
  for (size_t k = 0; k < floor.facades.size(); ++k) {
    const FloorRect& r = floor.facades[k];
    PlannedCell cell;
    cell.kind = CellKind::Facade;
    cell.name = fmt::format("facade-{}", k);
    cell.box = Bounds3(Vec3(r.x0, 0, r.z0), Vec3(r.x1, plan.top, r.z1));
    plan.cells.push_back(std::move(cell));
  }
  plan.floorCells = floor.cells.size();
}

// The camera looks down on the top floor from the south; the sky cell,
// added last, holds it.
Camera addSkyAndCamera(BuildingPlan& plan) {
  Bounds3 footprint;
  for (const PlannedCell& cell : plan.cells) footprint.extend(cell.box);
  Camera camera;
  camera.name = "overview";
  const Vec3 centre((footprint.lo.x + footprint.hi.x) * 0.5f, plan.top - kStorey, (footprint.lo.z + footprint.hi.z) * 0.5f);
  const float scale = 1.1f * std::max((footprint.hi.x - footprint.lo.x) / 14.0f, (footprint.hi.z - footprint.lo.z) / 10.0f);
  camera.origin = centre + Vec3(0.0f, 16.0f * scale, -10.0f * scale);
  camera.target = centre;
  camera.fovYDegrees = 40.0f;
  camera.width = 480;
  camera.height = 320;
  PlannedCell sky;
  sky.kind = CellKind::Sky;
  sky.name = "sky";
  sky.box = Bounds3(Vec3(footprint.lo.x - 2, plan.top, footprint.lo.z - 2),
                    Vec3(footprint.hi.x + 2, plan.top + kSkyHeight, footprint.hi.z + 2));
  sky.box.extend(Bounds3(camera.origin - Vec3(1), camera.origin + Vec3(1)));
  plan.cells.push_back(std::move(sky));
  plan.skyId = uint32_t(plan.cells.size() - 1);
  camera.cell = plan.skyId;
  return camera;
}

// Standing cameras on every floor: in the room with the most lights (on a
// tie the largest, then the first), named "floorF-room-...", and in the
// floor's first corridor, "floorF-corridor".
void addInteriorCameras(const BuildingPlan& plan, const Camera& overview, SceneStoreWriter& writer) {
  const auto camera = [&](std::string name, uint32_t id) {
    const PlannedCell& cell = plan.cells[id];
    writer.addCamera(standingCamera(std::move(name), id, cell.box.lo.y, cell.source->viewFrom, cell.source->viewTo,
                                    overview.width, overview.height));
  };
  const uint32_t floors = plan.floorCells == 0 ? 0 : uint32_t(plan.firstFacade / plan.floorCells);
  for (uint32_t f = 0; f < floors; ++f) {
    std::optional<uint32_t> room, corridor;
    for (uint32_t id = uint32_t(f * plan.floorCells); id < uint32_t((f + 1) * plan.floorCells); ++id) {
      const PlannedCell& cell = plan.cells[id];
      if (cell.kind == CellKind::Corridor && !corridor) corridor = id;
      if (cell.kind != CellKind::Room) continue;
      if (!room) {
        room = id;
        continue;
      }
      const PlannedCell& best = plan.cells[*room];
      if (cell.lights.size() > best.lights.size() ||
          (cell.lights.size() == best.lights.size() && area(cell.source->rect) > area(best.source->rect)))
        room = id;
    }
    if (room) camera(fmt::format("floor{}-{}", f, plan.cells[*room].source->name), *room);
    if (corridor) camera(fmt::format("floor{}-corridor", f), *corridor);
  }
}

// Portals: the floor's own, stairs between floors, windows, and the sky.
void addPortals(const BuildingPreset& preset, const FloorTemplate& floor, BuildingPlan& plan, SceneStoreWriter& writer) {
  const auto addPortal = [&](uint32_t a, uint32_t b, const std::vector<Vec3>& polygon) {
    const uint32_t id = writer.addPortal(a, b, polygon);
    plan.portalPolygons.push_back(polygon);
    plan.cells[a].portals.push_back(id);
    plan.cells[b].portals.push_back(id);
  };
  const auto lifted = [](std::vector<Vec3> polygon, float y) {
    for (Vec3& v : polygon) v.y += y;
    return polygon;
  };
  for (uint32_t f = 0; f < preset.floors; ++f) {
    const uint32_t base = uint32_t(f * plan.floorCells);
    const float y = kStorey * float(f);
    for (const TemplatePortal& p : floor.portals) addPortal(base + uint32_t(p.a), base + uint32_t(p.b), lifted(p.polygon, y));
    for (const Window& w : floor.windows)
      addPortal(base + uint32_t(w.room), uint32_t(plan.firstFacade + w.facade), lifted(w.polygon, y));
    if (f + 1 < preset.floors)
      for (size_t j : floor.junctions) {
        const FloorRect& o = floor.cells[j].stair.opening;
        const float up = kStorey * float(f + 1);
        addPortal(base + uint32_t(j), base + uint32_t(plan.floorCells + j),
                  {Vec3(o.x0, up, o.z0), Vec3(o.x1, up, o.z0), Vec3(o.x1, up, o.z1), Vec3(o.x0, up, o.z1)});
      }
  }
  const float top = plan.top;
  for (uint32_t id = 0; id < plan.skyId; ++id) {
    if (plan.cells[id].box.hi.y < top - 1e-3f) continue;   // only the top floor and the facades reach the sky
    const Bounds3& b = plan.cells[id].box;
    addPortal(id, plan.skyId,
              {Vec3(b.lo.x, top, b.lo.z), Vec3(b.hi.x, top, b.lo.z), Vec3(b.hi.x, top, b.hi.z), Vec3(b.lo.x, top, b.hi.z)});
  }
}

// Lights by floor area over the rooms, corridors and junctions (some rooms
// get none when there are fewer lights than rooms: lit through doors).
// Returns how many.
uint32_t addLights(const BuildingPreset& preset, BuildingPlan& plan, SceneStoreWriter& writer, PanelMaterials& panels) {
  std::vector<PlannedCell>& cells = plan.cells;
  std::vector<double> lightWeights(cells.size(), 0.0);
  std::vector<uint64_t> lightCaps(cells.size(), 0);
  for (size_t i = 0; i < cells.size(); ++i)
    if (cells[i].source) {
      lightWeights[i] = area(cells[i].source->rect);
      lightCaps[i] = uint64_t(std::max(1.0f, area(cells[i].source->lightArea) / 1.0f));
    }
  const std::vector<uint64_t> lightCounts = largestRemainderShares(preset.lights, lightWeights, lightCaps);
  uint32_t lightTotal = 0;
  for (size_t i = 0; i < cells.size(); ++i) {
    if (!cells[i].source) continue;
    const FloorRect shrunk{cells[i].source->lightArea.x0 + 0.3f, cells[i].source->lightArea.x1 - 0.3f,
                           cells[i].source->lightArea.z0 + 0.3f, cells[i].source->lightArea.z1 - 0.3f};
    cells[i].lights = lightGrid(shrunk, cells[i].box.lo.y + kCeiling, uint32_t(lightCounts[i]), uint32_t(i));
    for (AreaLight& light : cells[i].lights) {
      cells[i].lightMaterials.push_back(panels.light(light));
      light.id = writer.addLight(light), ++lightTotal;
    }
  }
  return lightTotal;
}

// The geometry of a cell except its furniture: floor, ceiling and walls
// with the holes of its portals, its lamps, and its stair.
void addShell(const PlannedCell& cell, const BuildingPlan& plan, const FurnitureMaterials& materials, MeshBuilder& mesh) {
  if (!cell.source) return;
  const Bounds3& box = cell.box;
  std::vector<PlaneRect> holes[3][2];
  for (uint32_t p : cell.portals)
    if (auto hole = holeOf(box, plan.portalPolygons[p])) holes[hole->axis][hole->high].push_back(hole->rect);
  const uint32_t floorMaterial = cell.kind == CellKind::Room ? materials.roomFloor : materials.corridorFloor;
  mesh.addAxisRectangle(1, box.lo.y, true, PlaneRect{box.lo.z, box.hi.z, box.lo.x, box.hi.x}, floorMaterial, holes[1][0]);
  mesh.addAxisRectangle(1, box.lo.y + kCeiling, false, PlaneRect{box.lo.z, box.hi.z, box.lo.x, box.hi.x},
                        materials.ceiling, holes[1][1]);
  const PlaneRect zWall{box.lo.x, box.hi.x, box.lo.y, box.hi.y};
  mesh.addAxisRectangle(2, box.lo.z, true, zWall, materials.wall, holes[2][0]);
  mesh.addAxisRectangle(2, box.hi.z, false, zWall, materials.wall, holes[2][1]);
  const PlaneRect xWall{box.lo.y, box.hi.y, box.lo.z, box.hi.z};
  mesh.addAxisRectangle(0, box.lo.x, true, xWall, materials.wall, holes[0][0]);
  mesh.addAxisRectangle(0, box.hi.x, false, xWall, materials.wall, holes[0][1]);
  for (size_t k = 0; k < cell.lights.size(); ++k) {
    const AreaLight& light = cell.lights[k];
    mesh.addParallelogram(light.corner, light.edge1, light.edge2, cell.lightMaterials[k]);
  }
  if (cell.stairUp)
    for (const Bounds3& step : cell.source->stair.steps)
      mesh.addBox(Bounds3(step.lo + Vec3(0, box.lo.y, 0), step.hi + Vec3(0, box.lo.y, 0)), materials.stair, false);
}

// The rooms' triangle budgets, from what the other cells leave of the
// preset's: the heaviest room gets the paper's maximum; the others share
// the rest by weight, each kept under 90 % of the maximum.
std::vector<uint64_t> roomBudgets(const BuildingPreset& preset, const BuildingPlan& plan,
                                  const std::vector<uint32_t>& rooms, uint64_t otherTriangles) {
  const uint64_t roomBudget = preset.triangles > otherTriangles ? preset.triangles - otherTriangles : 0;
  std::vector<double> weights;
  for (uint32_t id : rooms) weights.push_back(plan.cells[id].source->weight);
  const size_t heaviest = size_t(std::max_element(weights.begin(), weights.end()) - weights.begin());
  const uint64_t heaviestBudget = std::min(roomBudget, preset.maxTrianglesPerCell);
  std::vector<double> otherWeights = weights;
  otherWeights[heaviest] = 0.0;
  std::vector<uint64_t> caps(rooms.size(), uint64_t(0.9 * double(preset.maxTrianglesPerCell)));
  std::vector<uint64_t> budgets = largestRemainderShares(roomBudget - heaviestBudget, otherWeights, caps);
  budgets[heaviest] = heaviestBudget;
  return budgets;
}

// Writes every cell's geometry: everything but the rooms first, then the
// rooms, furnished for what the others leave of the triangle budget.
// Returns the triangles written.
uint64_t writeCells(const BuildingPreset& preset, uint64_t seed, const BuildingPlan& plan,
                    const FurnitureMaterials& materials, SceneStoreWriter& writer) {
  uint64_t triangles = 0;
  const auto write = [&](uint32_t id, MeshBuilder& mesh) {
    CellContent content;
    content.id = id;
    content.name = plan.cells[id].name;
    content.bounds = plan.cells[id].box;
    mesh.moveInto(content);
    triangles += content.indices.size() / 3;
    writer.writeCell(content);
  };
  std::vector<uint32_t> rooms;
  for (uint32_t id = 0; id < plan.cells.size(); ++id) {
    if (plan.cells[id].kind == CellKind::Room) {
      rooms.push_back(id);
      continue;
    }
    MeshBuilder mesh;
    addShell(plan.cells[id], plan, materials, mesh);
    write(id, mesh);
  }
  const std::vector<uint64_t> budgets = roomBudgets(preset, plan, rooms, triangles);
  for (size_t k = 0; k < rooms.size(); ++k) {
    const uint32_t id = rooms[k];
    const PlannedCell& cell = plan.cells[id];
    MeshBuilder mesh;
    addShell(cell, plan, materials, mesh);
    const uint64_t shellTriangles = mesh.triangleCount();
    std::vector<furniture::PlacedPiece> pieces =
        furniture::arrangeRoom(cell.source->rect, cell.box.lo.y, cell.source->keepOut, preset.style, mix64(seed ^ mix64(id)));
    const uint64_t furnitureBudget = budgets[k] > shellTriangles ? budgets[k] - shellTriangles : 0;
    const float detail = furniture::chooseDetail(pieces, furnitureBudget);
    furniture::emitRoom(mesh, pieces, materials.pieces, detail);
    write(id, mesh);
  }
  return triangles;
}

}  // namespace

GeneratedBuildingStats generateBuilding(const BuildingPreset& preset, uint64_t seed, const std::string& storeDirectory,
                                        const PanelLighting& lighting) {
  if (const std::string problem = panelLightingProblem(lighting); !problem.empty()) throw std::invalid_argument(problem);
  const auto start = std::chrono::steady_clock::now();
  if (preset.floors == 0 || preset.cells == 0) throw std::runtime_error("preset " + preset.name + ": no floors or cells");
  DemoRandom random(seed);
  FloorPlanner planner(preset, random);
  const FloorTemplate floor = planner.plan(roomsPerWing(preset));
  BuildingPlan plan;
  planCells(preset, floor, plan);

  SceneStoreWriter writer(storeDirectory);
  writer.setMeta("generator", preset.name);
  writer.setMeta("seed", std::to_string(seed));
  writer.setMeta("floors", std::to_string(preset.floors));
  writer.setMeta("furnishing", preset.style == furniture::Style::Regular ? "regular" : "hand-made");
  const FurnitureMaterials materials = addMaterials(writer);
  const Camera overview = addSkyAndCamera(plan);
  writer.setCamera(overview);
  addPortals(preset, floor, plan, writer);
  GeneratedBuildingStats stats;
  PanelMaterials panels(writer, lighting, materials.light);
  stats.lights = addLights(preset, plan, writer, panels);
  addInteriorCameras(plan, overview, writer);
  stats.triangles = writeCells(preset, seed, plan, materials, writer);
  writer.commit();
  stats.cells = uint32_t(plan.cells.size());
  stats.portals = uint32_t(plan.portalPolygons.size());
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return stats;
}

}  // namespace portico
