// Meshes and rays shared by the accelerators' tests: triangle soups, rooms
// of boxes (shared faces, ties, duplicates), long thin triangles, degenerate
// triangles, a furnished hall, a dense cluster in a large empty room, and
// rays of every kind an accelerator must get right.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "common/accel/accelerator.h"
#include "common/mesh_view.h"
#include "common/ray.h"
#include "common/scene/generator/furnished_hall.h"

namespace portico::accel_test {

// A mesh owned by the test, viewed as the accelerators see cells.
struct TestMesh {
  std::vector<float> positions;
  std::vector<uint32_t> indices;

  uint32_t addVertex(const Vec3& p) {
    positions.insert(positions.end(), {p.x, p.y, p.z});
    return uint32_t(positions.size() / 3 - 1);
  }
  void addTriangle(const Vec3& a, const Vec3& b, const Vec3& c) {
    indices.insert(indices.end(), {addVertex(a), addVertex(b), addVertex(c)});
  }
  void addQuad(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
    // Shared vertices, so the two halves share an edge exactly.
    const uint32_t ia = addVertex(a), ib = addVertex(b), ic = addVertex(c), id = addVertex(d);
    indices.insert(indices.end(), {ia, ib, ic, ia, ic, id});
  }
  void addBox(const Vec3& lo, const Vec3& hi) {
    const Vec3 p[8] = {{lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z}, {lo.x, hi.y, lo.z},
                       {lo.x, lo.y, hi.z}, {hi.x, lo.y, hi.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z}};
    addQuad(p[0], p[1], p[2], p[3]);
    addQuad(p[4], p[5], p[6], p[7]);
    addQuad(p[0], p[1], p[5], p[4]);
    addQuad(p[3], p[2], p[6], p[7]);
    addQuad(p[0], p[3], p[7], p[4]);
    addQuad(p[1], p[2], p[6], p[5]);
  }
  Vec3 vertex(size_t i) const { return {positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]}; }
  size_t triangleCount() const { return indices.size() / 3; }
  MeshView view() const {
    MeshView mesh;
    mesh.positions = positions.data();
    mesh.vertexCount = positions.size() / 3;
    mesh.indices = indices.data();
    mesh.triangleCount = indices.size() / 3;
    return mesh;
  }
  Bounds3 bounds() const {
    Bounds3 box;
    for (size_t i = 0; i < positions.size() / 3; ++i) box.extend(vertex(i));
    return box;
  }
};

inline void addRandomTriangles(TestMesh& mesh, int count, std::mt19937& random) {
  std::uniform_real_distribution<float> position(0, 10), offset(-1, 1);
  const float sizes[] = {0.02f, 0.2f, 1.0f, 3.0f};
  for (int i = 0; i < count; ++i) {
    const Vec3 centre{position(random), position(random), position(random)};
    const float size = sizes[random() % 4];
    const auto corner = [&] { return centre + Vec3(offset(random), offset(random), offset(random)) * size; };
    mesh.addTriangle(corner(), corner(), corner());
  }
}

// A room of boxes on a 0.5 lattice: a shell, a wall, `boxes` boxes standing
// on the floor, every third with one stacked on it (shared faces: coplanar
// overlapping triangles, so ties), plus `duplicates` exact duplicates.
inline void addRoomOfBoxes(TestMesh& mesh, std::mt19937& random, int boxes = 30, int duplicates = 40) {
  mesh.addBox({0, 0, 0}, {10, 8, 3});
  mesh.addBox({4.5f, 0, 0}, {5, 8, 3});
  for (int i = 0; i < boxes; ++i) {
    const float x = 0.5f * float(random() % 18), y = 0.5f * float(random() % 14);
    const float w = 0.5f * float(1 + random() % 3), h = 0.5f * float(1 + random() % 3);
    mesh.addBox({x, y, 0}, {x + w, y + w, h});
    if (i % 3 == 0) mesh.addBox({x, y, h}, {x + w, y + w, h + 0.5f});  // stacked: shared face
  }
  const size_t existing = mesh.triangleCount();
  for (int i = 0; i < duplicates; ++i) {
    const uint32_t* t = &mesh.indices[3 * (random() % existing)];
    mesh.addTriangle(mesh.vertex(t[0]), mesh.vertex(t[1]), mesh.vertex(t[2]));
  }
}

// Long, thin triangles crossing the whole scene: each spans many voxels.
inline void addLongThinTriangles(TestMesh& mesh, int count, std::mt19937& random) {
  std::uniform_real_distribution<float> position(0, 10), width(-0.01f, 0.01f);
  for (int i = 0; i < count; ++i) {
    const Vec3 a{position(random), position(random), position(random)};
    const Vec3 b{position(random), position(random), position(random)};
    mesh.addTriangle(a, b, b + Vec3(width(random), width(random), width(random)));
  }
}

// A dense cluster of small triangles (and a few duplicates) in one corner
// of a large, empty room: the case sub-grids are for.
inline void addClusterInEmptyRoom(TestMesh& mesh, int count, std::mt19937& random) {
  mesh.addBox({0, 0, 0}, {40, 30, 10});
  std::uniform_real_distribution<float> position(1, 2.5f), offset(-0.05f, 0.05f);
  for (int i = 0; i < count; ++i) {
    const Vec3 centre{position(random), position(random), position(random)};
    const auto corner = [&] { return centre + Vec3(offset(random), offset(random), offset(random)); };
    mesh.addTriangle(corner(), corner(), corner());
  }
  for (int i = 0; i < 20; ++i) {
    const uint32_t* t = &mesh.indices[3 * (mesh.triangleCount() - 1 - random() % count)];
    mesh.addTriangle(mesh.vertex(t[0]), mesh.vertex(t[1]), mesh.vertex(t[2]));
  }
}

// Degenerate triangles (points, segments) and exact duplicates (same t,
// another id), some rotated.
inline void addDegenerateAndDuplicates(TestMesh& mesh, int count, std::mt19937& random) {
  const size_t existing = mesh.triangleCount();
  std::uniform_real_distribution<float> position(0, 10);
  for (int i = 0; i < count; ++i) {
    const Vec3 a{position(random), position(random), position(random)};
    const Vec3 b{position(random), position(random), position(random)};
    mesh.addTriangle(a, a, a);                   // a point
    mesh.addTriangle(a, b, a + (b - a) * 0.5f);  // (nearly) a segment
    if (existing > 0) {
      const uint32_t* t = &mesh.indices[3 * (random() % existing)];
      mesh.addTriangle(mesh.vertex(t[0]), mesh.vertex(t[1]), mesh.vertex(t[2]));  // same t, another id
      mesh.addTriangle(mesh.vertex(t[2]), mesh.vertex(t[0]), mesh.vertex(t[1]));  // rotated
    }
  }
}

// A floor of 20 x 20 unit quads at z = 1: every box of it is flat, and rays
// straight down onto its shared vertices and edges tie.
inline void addFloor(TestMesh& mesh) {
  for (int y = 0; y < 20; ++y)
    for (int x = 0; x < 20; ++x)
      mesh.addQuad({float(x), float(y), 1}, {float(x + 1), float(y), 1}, {float(x + 1), float(y + 1), 1},
                   {float(x), float(y + 1), 1});
}

// Moves the mesh as a cell of a large building lies: coordinates in the thousands.
inline void moveFarFromTheOrigin(TestMesh& mesh) {
  for (size_t i = 0; i < mesh.positions.size(); i += 3) {
    mesh.positions[i] += 3000.0f;
    mesh.positions[i + 1] -= 1200.0f;
    mesh.positions[i + 2] += 40.0f;
  }
}

// Gives a NaN or infinite vertex to the first triangle, the last, a run and
// every seventh (brute force never hits them).
inline void poisonSomeTriangles(TestMesh& mesh) {
  const size_t count = mesh.triangleCount();
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const auto poison = [&](size_t triangle, float value) { mesh.positions[3 * mesh.indices[3 * triangle] + 1] = value; };
  poison(0, nan);
  poison(count - 1, -inf);
  for (size_t t = count / 2; t < count / 2 + 5; ++t) poison(t, inf);
  for (size_t t = 3; t < count; t += 7) poison(t, nan);
}

inline TestMesh furnishedHall(size_t triangles, uint64_t seed) {
  const FurnishedHall hall = generateFurnishedHall(triangles, seed);
  TestMesh mesh;
  mesh.positions = hall.cell.positions;
  mesh.indices = hall.cell.indices;
  return mesh;
}

inline TestMesh mixedScene(uint32_t seed) {
  std::mt19937 random(seed);
  TestMesh mesh;
  addRandomTriangles(mesh, 400, random);
  addRoomOfBoxes(mesh, random);
  addLongThinTriangles(mesh, 40, random);
  return mesh;
}

// Rays of every kind: from inside and outside the bounds, along axes, through
// vertices (shared edges and corners: ties), finite segments, and with
// coordinates on the given planes (an accelerator's voxel boundaries).
// planeCoordinate(axis, random) returns a coordinate of such a plane.
inline std::vector<Ray> testRays(const TestMesh& mesh, int count, uint32_t seed,
                                 const std::function<float(int, std::mt19937&)>& planeCoordinate = {}) {
  std::mt19937 random(seed);
  const Bounds3 box = mesh.bounds();
  const Vec3 diagonal = box.diagonal();
  std::uniform_real_distribution<float> unit(0, 1), symmetric(-1, 1);
  const auto inside = [&] {
    return box.lo + Vec3(unit(random) * diagonal.x, unit(random) * diagonal.y, unit(random) * diagonal.z);
  };
  const auto anywhere = [&] {  // the bounds grown by one diagonal each side
    return box.center() + Vec3(symmetric(random) * 1.5f * diagonal.x, symmetric(random) * 1.5f * diagonal.y,
                               symmetric(random) * 1.5f * diagonal.z);
  };
  const auto randomDirection = [&] {
    Vec3 d;
    do d = {symmetric(random), symmetric(random), symmetric(random)};
    while (dot(d, d) < 1e-4f);
    return d * (0.1f + 3 * unit(random));  // not normalised
  };
  const auto axisDirection = [&] {
    Vec3 d(0.0f);
    const int axis = int(random() % 3);
    d[axis] = random() % 2 ? 1.0f : -1.0f;
    if (random() % 3 == 0) d[(axis + 1) % 3] = symmetric(random);  // one zero component
    return d;
  };
  const auto onPlanes = [&](Vec3 p) {
    if (!planeCoordinate) return p;
    for (int axis = 0; axis < 3; ++axis)
      if (random() % 2) p[axis] = planeCoordinate(axis, random);
    return p;
  };
  const auto meshVertex = [&] { return mesh.vertex(random() % (mesh.positions.size() / 3)); };

  std::vector<Ray> rays;
  for (int i = 0; i < count; ++i) {
    Ray ray;
    switch (i % 8) {
      case 0: ray = {inside(), randomDirection()}; break;
      case 1: ray = {anywhere(), randomDirection()}; break;
      case 2: ray = {inside(), axisDirection()}; break;
      case 3: ray = {onPlanes(inside()), random() % 2 ? axisDirection() : randomDirection()}; break;
      case 4: {
        const Vec3 origin = anywhere();
        ray = {origin, meshVertex() - origin};
        break;
      }
      case 5: {
        const Vec3 origin = anywhere();
        ray = {origin, inside() - origin};
        break;
      }
      case 6: ray = {onPlanes(anywhere()), axisDirection()}; break;
      case 7: {
        ray = {inside(), randomDirection()};
        ray.tMin = unit(random) < 0.5f ? 0.0f : unit(random);
        ray.tMax = ray.tMin + 3 * unit(random);
        break;
      }
    }
    rays.push_back(ray);
  }
  return rays;
}

// Rays that meet a triangle at a grazing angle: aimed at a point of a
// random triangle (inside it, or on an edge) from a direction tilted out of
// the triangle's plane by 1e-1 down to 1e-7 radians, starting before the
// point or on a surface just off it (as bounced photons leave surfaces).
// Where the watertight test's rounding is worst (nearly edge-on hits), so
// the tests that grow the hierarchies' boxes by a margin
// (common/accel/traversal_margin.h) are checked here.
inline std::vector<Ray> grazingRays(const TestMesh& mesh, int count, uint32_t seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> unit(0, 1), symmetric(-1, 1);
  std::vector<Ray> rays;
  const size_t triangles = mesh.triangleCount();
  for (int i = 0; i < count && triangles > 0; ++i) {
    const uint32_t* t = &mesh.indices[3 * (random() % triangles)];
    const Vec3 a = mesh.vertex(t[0]), b = mesh.vertex(t[1]), c = mesh.vertex(t[2]);
    const Vec3 normal = cross(b - a, c - a);
    if (!(dot(normal, normal) > 0)) continue;
    const Vec3 n = normalize(normal);
    float r = unit(random), s = unit(random);
    if (random() % 4 == 0) s = 0;   // on an edge
    if (r + s > 1) r = 1 - r, s = 1 - s;
    const Vec3 target = a + (b - a) * r + (c - a) * s;
    // A direction in the plane, tilted out of it.
    Vec3 inPlane = (b - a) * symmetric(random) + (c - a) * symmetric(random);
    if (!(dot(inPlane, inPlane) > 0)) inPlane = b - a;
    inPlane = normalize(inPlane - n * dot(inPlane, n));
    const float tilt = std::pow(10.0f, -1.0f - 6.0f * unit(random)) * (random() % 2 ? 1.0f : -1.0f);
    const Vec3 direction = normalize(inPlane + n * tilt);
    const float reach = length(b - a) + length(c - a);
    Ray ray;
    if (i % 3 == 2) {
      // Off the surface along its normal, then along the plane.
      const float offset = 2e-5f * std::max({1.0f, std::abs(target.x), std::abs(target.y), std::abs(target.z)});
      ray = {target + n * (tilt > 0 ? offset : -offset), direction};
    } else {
      ray = {target - direction * (reach * (0.01f + 2 * unit(random))), direction};
    }
    rays.push_back(ray);
  }
  return rays;
}

// What action throws as std::invalid_argument ("(no error)" if nothing).
inline std::string errorOf(const std::function<void()>& action) {
  try {
    action();
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "(no error)";
}

inline std::string describe(const Ray& ray) {
  std::ostringstream out;
  out.precision(9);
  out << "origin (" << ray.origin.x << ", " << ray.origin.y << ", " << ray.origin.z << ") direction ("
      << ray.direction.x << ", " << ray.direction.y << ", " << ray.direction.z << ") t (" << ray.tMin << ", "
      << ray.tMax << ")";
  return out.str();
}

inline bool sameBits(const Hit& a, const Hit& b) {
  return a.primitive == b.primitive && std::bit_cast<uint32_t>(a.t) == std::bit_cast<uint32_t>(b.t) &&
         std::bit_cast<uint32_t>(a.u) == std::bit_cast<uint32_t>(b.u) &&
         std::bit_cast<uint32_t>(a.v) == std::bit_cast<uint32_t>(b.v);
}

// Asks `accelerator` every ray from 4 threads at once, `passes` times each,
// and counts per thread the answers that differ from single-threaded ones:
// same(hit, expected) decides whether two hits agree; occluded() must agree.
template <class Accelerator, class Same>
std::vector<int> mismatchesFromManyThreads(const Accelerator& accelerator, const std::vector<Ray>& rays,
                                           int passes, Same same) {
  std::vector<Hit> expected;
  for (const Ray& ray : rays) expected.push_back(accelerator.intersect(ray));
  std::vector<int> mismatches(4, 0);
  std::vector<std::thread> threads;
  for (int thread = 0; thread < 4; ++thread)
    threads.emplace_back([&, thread] {
      for (int pass = 0; pass < passes; ++pass)
        for (size_t i = 0; i < rays.size(); ++i)
          mismatches[thread] += !same(accelerator.intersect(rays[i]), expected[i]) ||
                                accelerator.occluded(rays[i]) != expected[i].found();
    });
  for (std::thread& thread : threads) thread.join();
  return mismatches;
}

}  // namespace portico::accel_test
