#include "common/scene/generator/furnished_hall.h"

#include <algorithm>
#include <cmath>

#include "common/scene/generator/demo_furniture.h"
#include "common/scene/generator/mesh_builder.h"

namespace portico {

namespace {

constexpr float kZoneWidth = 4.0f;      // along x
constexpr float kZoneDepth = 4.5f;      // along z
constexpr float kHallHeight = 3.0f;
constexpr float kEyeHeight = 2.4f;      // above the tallest piece (bookshelves, ~2.15 m)
constexpr float kDoorClearance = 0.8f;  // the free strip of each zone (a walkway)
constexpr size_t kShellTriangles = 12;
constexpr uint32_t kMaxZones = 1u << 20;

demo::DemoMaterials hallMaterials() {
  demo::DemoMaterials m{};
  m.roomFloor = 0, m.corridorFloor = 0, m.wall = 1;
  m.accentWalls[0] = m.accentWalls[1] = m.accentWalls[2] = 1;
  m.wood = 2, m.darkWood = 3, m.cabinet = 4, m.metal = 5;
  m.fabrics[0] = 6, m.fabrics[1] = 7, m.fabrics[2] = 8;
  m.books[0] = 9, m.books[1] = 10, m.books[2] = 11;
  m.light = 12;
  return m;
}

demo::RoomFrame zoneFrame(uint32_t zone, uint32_t columns) {
  demo::RoomFrame frame;
  frame.x0 = float(zone % columns) * kZoneWidth;
  frame.width = kZoneWidth;
  frame.depth = kZoneDepth;
  frame.corridorWallZ = float(zone / columns) * kZoneDepth;
  frame.awayFromCorridor = 1.0f;
  return frame;
}

// Appends triangle (a, b, c) split into k * k triangles of the same winding,
// stopping once `out` holds `limit` triangles. Lattice points are weighted
// sums of the corners, so the corners themselves are reproduced exactly.
void appendTessellated(const Vec3& a, const Vec3& b, const Vec3& c, uint32_t material, int k, size_t limit,
                       CellContent& out) {
  const auto point = [&](int i, int j) {
    const float wb = float(i) / float(k), wc = float(j) / float(k), wa = float(k - i - j) / float(k);
    return a * wa + b * wb + c * wc;
  };
  const auto vertex = [&](int i, int j) {
    const Vec3 p = point(i, j);
    out.positions.insert(out.positions.end(), {p.x, p.y, p.z});
    return uint32_t(out.positions.size() / 3 - 1);
  };
  // Row by row: lattice row j holds points i = 0 .. k - j.
  std::vector<uint32_t> below, above;
  for (int i = 0; i <= k; ++i) below.push_back(vertex(i, 0));
  for (int j = 0; j < k; ++j) {
    above.clear();
    for (int i = 0; i <= k - j - 1; ++i) above.push_back(vertex(i, j + 1));
    for (int i = 0; i < k - j; ++i) {
      if (out.indices.size() / 3 >= limit) return;
      out.indices.insert(out.indices.end(), {below[i], below[i + 1], above[i]});
      out.materials.push_back(material);
      if (i + 1 < k - j) {
        if (out.indices.size() / 3 >= limit) return;
        out.indices.insert(out.indices.end(), {below[i + 1], above[i + 1], above[i]});
        out.materials.push_back(material);
      }
    }
    below.swap(above);
  }
}

// Furniture triangles of one zone at tessellation 1.
CellContent furnishZone(uint32_t zone, uint32_t columns, const demo::DemoMaterials& materials,
                        demo::DemoRandom& random) {
  MeshBuilder mesh;
  demo::furnishRoom(mesh, zoneFrame(zone, columns), materials, random, kDoorClearance);
  CellContent content;
  mesh.moveInto(content);
  return content;
}

}  // namespace

FurnishedHall generateFurnishedHall(size_t triangles, uint64_t seed) {
  const demo::DemoMaterials materials = hallMaterials();
  const size_t furnitureTarget = triangles > kShellTriangles ? triangles - kShellTriangles : 0;

  // Furniture triangles per zone, from a pilot run of a few zones.
  demo::DemoRandom pilotRandom(seed ^ 0x9e3779b97f4a7c15ull);
  size_t pilotTriangles = 0;
  constexpr uint32_t kPilotZones = 16;
  for (uint32_t zone = 0; zone < kPilotZones; ++zone)
    pilotTriangles += furnishZone(zone, 4, materials, pilotRandom).indices.size() / 3;
  const double perZone = std::max(1.0, double(pilotTriangles) / kPilotZones);

  // About sqrt(n) / 10 zones; the tessellation makes up the rest.
  const double plannedZones = std::max(1.0, std::round(std::sqrt(double(triangles)) / 10.0));
  FurnishedHall hall;
  hall.tessellation =
      std::max(1, int(std::lround(std::sqrt(double(furnitureTarget) / (plannedZones * perZone)))));
  const double zonesNeeded =
      std::max(1.0, std::ceil(double(furnitureTarget) / (perZone * hall.tessellation * hall.tessellation)));
  // A near-square hall: columns * width ~ rows * depth.
  const uint32_t columns =
      std::max(1u, uint32_t(std::ceil(std::sqrt(zonesNeeded * kZoneDepth / kZoneWidth))));

  // Furniture, zone after zone, until the count is reached.
  CellContent furniture;
  demo::DemoRandom random(seed);
  uint32_t zone = 0;
  while (furniture.indices.size() / 3 < furnitureTarget && zone < kMaxZones) {
    const CellContent pieces = furnishZone(zone++, columns, materials, random);
    for (size_t t = 0; t < pieces.indices.size() / 3; ++t) {
      const auto corner = [&](int i) {
        const uint32_t v = pieces.indices[3 * t + i];
        return Vec3(pieces.positions[3 * v], pieces.positions[3 * v + 1], pieces.positions[3 * v + 2]);
      };
      appendTessellated(corner(0), corner(1), corner(2), pieces.materials[t], hall.tessellation,
                        furnitureTarget, furniture);
    }
  }
  hall.zones = zone;

  // The shell, facing in, around every zone used; then the furniture.
  const uint32_t rows = std::max(1u, (zone + columns - 1) / columns);
  const Bounds3 box(Vec3(0.0f, 0.0f, 0.0f),
                    Vec3(float(std::min(zone, columns)) * kZoneWidth, kHallHeight, float(rows) * kZoneDepth));
  MeshBuilder shell;
  const PlaneRect footprint{box.lo.z, box.hi.z, box.lo.x, box.hi.x};
  shell.addAxisRectangle(1, box.lo.y, true, footprint, materials.roomFloor);
  shell.addAxisRectangle(1, box.hi.y, false, footprint, materials.wall);
  const PlaneRect zWall{box.lo.x, box.hi.x, box.lo.y, box.hi.y};
  shell.addAxisRectangle(2, box.lo.z, true, zWall, materials.wall);
  shell.addAxisRectangle(2, box.hi.z, false, zWall, materials.wall);
  const PlaneRect xWall{box.lo.y, box.hi.y, box.lo.z, box.hi.z};
  shell.addAxisRectangle(0, box.lo.x, true, xWall, materials.wall);
  shell.addAxisRectangle(0, box.hi.x, false, xWall, materials.wall);
  shell.moveInto(hall.cell);

  const uint32_t shellVertices = uint32_t(hall.cell.positions.size() / 3);
  const size_t shellKept = std::min(hall.cell.indices.size() / 3, triangles);
  hall.cell.indices.resize(3 * shellKept);
  hall.cell.materials.resize(shellKept);
  hall.cell.positions.insert(hall.cell.positions.end(), furniture.positions.begin(), furniture.positions.end());
  for (uint32_t index : furniture.indices) hall.cell.indices.push_back(index + shellVertices);
  hall.cell.materials.insert(hall.cell.materials.end(), furniture.materials.begin(), furniture.materials.end());
  hall.cell.name = "furnished-hall";
  hall.cell.bounds = box;
  hall.eye = Vec3(0.5f * (box.lo.x + box.hi.x), kEyeHeight, 0.5f * (box.lo.z + box.hi.z));
  return hall;
}

}  // namespace portico
