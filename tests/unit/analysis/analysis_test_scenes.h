// Hand-made rooms for the lighting-analysis tests: boxes of quads written
// to a real scene store.
#pragma once

#include <string>
#include <vector>

#include "common/scene/store/scene_store.h"

namespace portico::testing_support {

// Triangles of one cell, built quad by quad.
struct CellMesh {
  std::vector<float> positions;
  std::vector<uint32_t> indices;

  // The quad a-b-c-d as two triangles; its front is cross(b - a, c - a).
  void quad(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
    const auto base = uint32_t(positions.size() / 3);
    for (const Vec3& v : {a, b, c, d}) positions.insert(positions.end(), {v.x, v.y, v.z});
    indices.insert(indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
  }
  // A level rectangle [x0, x1] x [z0, z1] at height y, facing up or down.
  void level(float x0, float z0, float x1, float z1, float y, bool up) {
    if (up)
      quad(Vec3(x0, y, z0), Vec3(x0, y, z1), Vec3(x1, y, z1), Vec3(x1, y, z0));
    else
      quad(Vec3(x0, y, z0), Vec3(x1, y, z0), Vec3(x1, y, z1), Vec3(x0, y, z1));
  }
  // A closed box (furniture, a cupboard) facing out, or a room's shell
  // facing in (floor up, ceiling down): its six faces.
  void box(const Vec3& lo, const Vec3& hi, bool inward = false) {
    level(lo.x, lo.z, hi.x, hi.z, hi.y, !inward);
    level(lo.x, lo.z, hi.x, hi.z, lo.y, inward);
    wallX(lo.x, lo.z, hi.z, lo.y, hi.y);
    wallX(hi.x, lo.z, hi.z, lo.y, hi.y);
    wallZ(lo.z, lo.x, hi.x, lo.y, hi.y);
    wallZ(hi.z, lo.x, hi.x, lo.y, hi.y);
  }
  // Vertical walls: the plane x = x (z from z0 to z1) or z = z.
  void wallX(float x, float z0, float z1, float y0, float y1) {
    quad(Vec3(x, y0, z0), Vec3(x, y1, z0), Vec3(x, y1, z1), Vec3(x, y0, z1));
  }
  void wallZ(float z, float x0, float x1, float y0, float y1) {
    quad(Vec3(x0, y0, z), Vec3(x1, y0, z), Vec3(x1, y1, z), Vec3(x0, y1, z));
  }
};

struct TestCell {
  std::string name;
  Bounds3 bounds;
  CellMesh mesh;
};

// A 6 m x 4 m room, 3 m tall, its floor at y = floorY: floor, ceiling, four walls.
inline TestCell boxRoom(const std::string& name, float floorY) {
  TestCell cell{name, Bounds3(Vec3(0, floorY, 0), Vec3(6, floorY + 3, 4)), {}};
  cell.mesh.box(cell.bounds.lo, cell.bounds.hi, true);
  return cell;
}

// A portal between two cells, a polygon.
struct TestPortal {
  uint32_t cellA = 0, cellB = 0;
  std::vector<Vec3> polygon;
};

// Writes the cells (one grey material, the camera in cell 0) and portals
// as a scene store at `directory`.
inline void writeTestStore(const std::string& directory, const std::vector<TestCell>& cells,
                           const std::vector<TestPortal>& portals = {}) {
  SceneStoreWriter writer(directory);
  writer.addMaterial("grey", Vec3(0.5f));
  for (const TestPortal& portal : portals) writer.addPortal(portal.cellA, portal.cellB, portal.polygon);
  for (uint32_t id = 0; id < cells.size(); ++id) {
    CellContent content;
    content.id = id;
    content.name = cells[id].name;
    content.bounds = cells[id].bounds;
    content.positions = cells[id].mesh.positions;
    content.indices = cells[id].mesh.indices;
    content.materials.assign(content.indices.size() / 3, 0);
    writer.writeCell(content);
  }
  Camera camera;
  camera.origin = cells[0].bounds.center();
  camera.target = camera.origin + Vec3(1, 0, 0);
  camera.cell = 0;
  writer.setCamera(camera);
  writer.commit();
}

}  // namespace portico::testing_support
