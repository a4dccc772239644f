// What the kd-tree builders share: the triangles that go in a tree, the
// limits, clipping (perfect splits), the writer of the flat node array, and
// the reference-based builder behind kd:median and kd:bbox.
#include "common/accel/kd_build.h"

#include <algorithm>
#include <bit>
#include <limits>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "common/accel/triangle_intersect.h"

namespace portico {

// ---------------------------------------------------------------------------
// Triangles and limits

std::vector<uint32_t> kdTreeTriangles(const MeshView& mesh) {
  std::vector<uint32_t> triangles;
  triangles.reserve(mesh.triangleCount);
  for (uint32_t primitive = 0; primitive < uint32_t(mesh.triangleCount); ++primitive) {
    Vec3 v0, v1, v2;
    mesh.triangle(primitive, v0, v1, v2);
    if (!isFinite(v0) || !isFinite(v1) || !isFinite(v2)) continue;  // refused at import; never hit
    if (isDegenerateTriangle(v0, v1, v2)) continue;                  // intersectTriangle never hits it
    triangles.push_back(primitive);
  }
  return triangles;
}

KdBuildLimits kdBuildLimits(const KdTreeOptions& options, size_t triangleCount) {
  KdBuildLimits limits;
  if (options.leafSize >= 0)
    limits.leafSize = uint32_t(options.leafSize);
  else
    limits.leafSize = options.strategy == KdSplitStrategy::SurfaceArea ? 0
                      : options.strategy == KdSplitStrategy::Median  ? 8
                                                                      : 4;
  if (options.maxDepth > 0) {
    limits.maxDepth = uint32_t(std::min(options.maxDepth, kKdMaxDepthLimit));
  } else {
    const double automatic = 8.0 + 1.3 * std::log2(std::max<double>(1.0, double(triangleCount)));
    limits.maxDepth = uint32_t(std::clamp(std::lround(automatic), 1L, long(kKdMaxDepthLimit)));
  }
  return limits;
}

// ---------------------------------------------------------------------------
// Clipping

namespace {

// The next float towards -infinity, +infinity from a finite f (as
// std::nextafter, without its call: clipping rounds every coordinate).
float nextDown(float f) {
  if (f == 0.0f) return -std::numeric_limits<float>::denorm_min();
  const uint32_t bits = std::bit_cast<uint32_t>(f);
  return std::bit_cast<float>(f > 0.0f ? bits - 1 : bits + 1);
}
float nextUp(float f) { return -nextDown(-f); }

// Largest float <= value, smallest float >= value (value within float range).
float floatBelow(double value) {
  const float f = static_cast<float>(value);
  return double(f) > value ? nextDown(f) : f;
}
float floatAbove(double value) {
  const float f = static_cast<float>(value);
  return double(f) < value ? nextUp(f) : f;
}

struct Point {
  double c[3];
};

// Sutherland-Hodgman against one axis-aligned plane: keeps the side where
// sign * (p[axis] - plane) >= 0. New points lie exactly on the plane.
int clipPolygon(const Point* in, int count, Point* out, int axis, double plane, double sign) {
  int written = 0;
  for (int i = 0; i < count; ++i) {
    const Point& a = in[i];
    const Point& b = in[i + 1 < count ? i + 1 : 0];
    const double da = sign * (a.c[axis] - plane), db = sign * (b.c[axis] - plane);
    if (da >= 0) out[written++] = a;
    if ((da >= 0) != (db >= 0)) {
      const double t = da / (da - db);
      Point p;
      for (int k = 0; k < 3; ++k) p.c[k] = a.c[k] + t * (b.c[k] - a.c[k]);
      p.c[axis] = plane;
      out[written++] = p;
    }
  }
  return written;
}

// Bounds of a polygon rounded outwards to float, kept within box and the
// triangle's own bounds (both exact), so that only interpolated
// coordinates move. Empty for an empty polygon.
Bounds3 polygonBounds(const Point* polygon, int count, const Bounds3& box, const Bounds3& triangle) {
  if (count == 0) return Bounds3();
  Bounds3 bounds;
  for (int axis = 0; axis < 3; ++axis) {
    double lo = polygon[0].c[axis], hi = lo;
    for (int i = 1; i < count; ++i) {
      lo = std::min(lo, polygon[i].c[axis]);
      hi = std::max(hi, polygon[i].c[axis]);
    }
    bounds.lo[axis] = std::max({floatBelow(lo), box.lo[axis], triangle.lo[axis]});
    bounds.hi[axis] = std::min({floatAbove(hi), box.hi[axis], triangle.hi[axis]});
    if (bounds.lo[axis] > bounds.hi[axis]) return Bounds3();
  }
  return bounds;
}

// The triangle clipped to box (only by the planes it crosses) into
// buffers[result]; returns the vertex count, 0 when they do not meet.
int clipToBox(const Vec3& v0, const Vec3& v1, const Vec3& v2, const Bounds3& triangle,
              const Bounds3& box, Point (&buffers)[2][9], int& result) {
  int count = 3;
  buffers[0][0] = {{v0.x, v0.y, v0.z}};
  buffers[0][1] = {{v1.x, v1.y, v1.z}};
  buffers[0][2] = {{v2.x, v2.y, v2.z}};
  int current = 0;
  for (int axis = 0; axis < 3 && count > 0; ++axis) {
    if (triangle.lo[axis] < box.lo[axis]) {
      count = clipPolygon(buffers[current], count, buffers[1 - current], axis, box.lo[axis], 1.0);
      current = 1 - current;
    }
    if (count > 0 && triangle.hi[axis] > box.hi[axis]) {
      count = clipPolygon(buffers[current], count, buffers[1 - current], axis, box.hi[axis], -1.0);
      current = 1 - current;
    }
  }
  result = current;
  return count;
}

Bounds3 triangleBounds(const Vec3& v0, const Vec3& v1, const Vec3& v2) {
  Bounds3 triangle(v0, v0);
  triangle.extend(v1);
  triangle.extend(v2);
  return triangle;
}

}  // namespace

void clipTriangleToChildren(const Vec3& v0, const Vec3& v1, const Vec3& v2, const Bounds3& box,
                            int axis, float position, Bounds3& below, Bounds3& above) {
  const Bounds3 triangle = triangleBounds(v0, v1, v2);
  const Bounds3 belowBox = boxBelow(box, axis, position), aboveBox = boxAbove(box, axis, position);
  // Clip to the node's box once, then split that polygon by the plane.
  Point buffers[2][9];
  int result = 0;
  const int count = clipToBox(v0, v1, v2, triangle, box, buffers, result);
  Point belowPolygon[10], abovePolygon[10];
  const int belowCount = clipPolygon(buffers[result], count, belowPolygon, axis, position, -1.0);
  const int aboveCount = clipPolygon(buffers[result], count, abovePolygon, axis, position, 1.0);
  below = polygonBounds(belowPolygon, belowCount, belowBox, triangle);
  above = polygonBounds(abovePolygon, aboveCount, aboveBox, triangle);
}

void splitTriangleToChildren(const Vec3& v0, const Vec3& v1, const Vec3& v2, const Bounds3& box, int axis,
                             float position, Bounds3& below, Bounds3& above) {
  // The same bounds as polygonBounds of the parts (with clipPolygon's
  // crossings), built directly: the corners are floats already, and only
  // the crossings are rounded outwards (kept within the triangle's bounds).
  const float corners[3][3] = {{v0.x, v0.y, v0.z}, {v1.x, v1.y, v1.z}, {v2.x, v2.y, v2.z}};
  const Bounds3 triangle = triangleBounds(v0, v1, v2);
  Bounds3 parts[2];  // below, above
  double distance[3];
  for (int i = 0; i < 3; ++i) distance[i] = double(corners[i][axis]) - double(position);
  for (int i = 0; i < 3; ++i) {
    const Vec3 corner(corners[i][0], corners[i][1], corners[i][2]);
    if (distance[i] <= 0) parts[0].extend(corner);
    if (distance[i] >= 0) parts[1].extend(corner);
    const int j = i == 2 ? 0 : i + 1;
    if (!((distance[i] < 0 && distance[j] > 0) || (distance[i] > 0 && distance[j] < 0))) continue;
    const double t = distance[i] / (distance[i] - distance[j]);
    Bounds3 crossing;
    for (int k = 0; k < 3; ++k) {
      const double c = k == axis ? double(position) : corners[i][k] + t * (double(corners[j][k]) - corners[i][k]);
      crossing.lo[k] = std::max(floatBelow(c), triangle.lo[k]);
      crossing.hi[k] = std::min(floatAbove(c), triangle.hi[k]);
    }
    parts[0].extend(crossing);
    parts[1].extend(crossing);
  }
  const Bounds3 halves[2] = {boxBelow(box, axis, position), boxAbove(box, axis, position)};
  for (int side = 0; side < 2; ++side) {
    parts[side].lo = max(parts[side].lo, halves[side].lo);
    parts[side].hi = min(parts[side].hi, halves[side].hi);
    if (parts[side].empty()) parts[side] = Bounds3();
  }
  below = parts[0];
  above = parts[1];
}

// ---------------------------------------------------------------------------
// Writer

KdTreeWriter::KdTreeWriter(KdTreeData& tree) : tree_(tree) {}

uint32_t KdTreeWriter::root() {
  // Node 1 is padding, so that every pair of children starts at an even
  // index: 16-byte aligned, a pair never straddles a cache line.
  tree_.nodes.assign(2, KdNode::leaf(0, 0));
  return 0;
}

uint32_t KdTreeWriter::split(uint32_t node, int axis, float position) {
  const size_t first = tree_.nodes.size();
  if (first + 1 > KdNode::kMaxIndex)
    throw std::length_error("kd-tree: more than 2^30 nodes; lower depth or split the cell");
  // Two push_backs rather than resize: their in-capacity path is inline
  // (resize calls out every time), and this runs once per interior node.
  tree_.nodes.push_back(KdNode::leaf(0, 0));
  tree_.nodes.push_back(KdNode::leaf(0, 0));
  tree_.nodes[node] = KdNode::interior(axis, position, uint32_t(first));
  return uint32_t(first);
}

void KdTreeWriter::leaf(uint32_t node, std::span<const uint32_t> triangles, uint32_t depth) {
  const size_t count = triangles.size();
  if (count > KdNode::kMaxIndex)
    throw std::length_error("kd-tree: a leaf of more than 2^30 triangles; split the cell");
  ++tree_.leaves;
  tree_.maxDepth = std::max(tree_.maxDepth, depth);
  if (count == 0) {
    ++tree_.emptyLeaves;
    tree_.nodes[node] = KdNode::leaf(0, 0);
    return;
  }
  tree_.triangleReferences += count;
  tree_.depthSum += depth;
  if (count == 1) {
    tree_.nodes[node] = KdNode::leaf(1, triangles[0]);
    return;
  }
  const size_t offset = tree_.primitives.size();
  if (offset + count > UINT32_MAX)
    throw std::length_error("kd-tree: more than 2^32 triangle references; lower depth or split the cell");
  tree_.primitives.insert(tree_.primitives.end(), triangles.begin(), triangles.end());
  tree_.nodes[node] = KdNode::leaf(uint32_t(count), uint32_t(offset));
}

// ---------------------------------------------------------------------------
// Reference-based builder

namespace {

class ReferenceBuilder {
 public:
  ReferenceBuilder(const MeshView& mesh, const KdBuildLimits& limits, KdSplitChooser& chooser,
                   KdTreeData& tree)
      : mesh_(mesh), limits_(limits), chooser_(chooser), writer_(tree) {}

  void build(std::vector<KdReference> references, const Bounds3& box) {
    build(writer_.root(), std::move(references), box, 1, 0);
  }

 private:
  void makeLeaf(uint32_t node, std::vector<KdReference>& references, uint32_t depth) {
    leafScratch_.clear();
    for (const KdReference& reference : references) leafScratch_.push_back(reference.primitive);
    std::sort(leafScratch_.begin(), leafScratch_.end());
    writer_.leaf(node, leafScratch_, depth);
  }

  void build(uint32_t node, std::vector<KdReference> references, const Bounds3& box,
             uint32_t depth, int badRefines) {
    const size_t count = references.size();
    if (count <= limits_.leafSize || depth > limits_.maxDepth) return makeLeaf(node, references, depth);
    const std::optional<KdSplit> split = chooser_.choose(references, box);
    if (!split) return makeLeaf(node, references, depth);

    // Classify; clip the straddling triangles to each child's box.
    const Bounds3 belowBox = boxBelow(box, split->axis, split->position);
    const Bounds3 aboveBox = boxAbove(box, split->axis, split->position);
    std::vector<KdReference> below, above;
    below.reserve(count / 2 + 1);
    above.reserve(count / 2 + 1);
    for (const KdReference& reference : references) {
      switch (kdSideOf(reference.box, *split)) {
        case KdSide::Below: below.push_back(reference); break;
        case KdSide::Above: above.push_back(reference); break;
        case KdSide::Both: {
          Vec3 v0, v1, v2;
          mesh_.triangle(reference.primitive, v0, v1, v2);
          Bounds3 belowPart, abovePart;
          clipTriangleToChildren(v0, v1, v2, reference.box, split->axis, split->position, belowPart, abovePart);
          if (!belowPart.empty()) below.push_back({belowPart, reference.primitive});
          if (!abovePart.empty()) above.push_back({abovePart, reference.primitive});
          break;
        }
      }
    }
    // A split that leaves one child with every triangle only cuts off
    // space; a few on one path mean the triangles cannot be told apart
    // there (they share a vertex or overlap), and splitting on would only
    // copy them down to the depth limit.
    if (std::max(below.size(), above.size()) == count && ++badRefines >= 3)
      return makeLeaf(node, references, depth);
    std::vector<KdReference>().swap(references);

    const uint32_t children = writer_.split(node, split->axis, split->position);
    build(children, std::move(below), belowBox, depth + 1, badRefines);
    build(children + 1, std::move(above), aboveBox, depth + 1, badRefines);
  }

  const MeshView& mesh_;
  KdBuildLimits limits_;
  KdSplitChooser& chooser_;
  KdTreeWriter writer_;
  std::vector<uint32_t> leafScratch_;
};

}  // namespace

void buildKdTreeFromReferences(const MeshView& mesh, const KdTreeOptions& options,
                               KdSplitChooser& chooser, KdTreeData& tree) {
  const std::vector<uint32_t> triangles = kdTreeTriangles(mesh);
  if (triangles.empty()) return;
  std::vector<KdReference> references;
  references.reserve(triangles.size());
  for (uint32_t primitive : triangles) {
    references.push_back({mesh.triangleBounds(primitive), primitive});
    tree.bounds.extend(references.back().box);
  }
  ReferenceBuilder builder(mesh, kdBuildLimits(options, triangles.size()), chooser, tree);
  builder.build(std::move(references), tree.bounds);
}

}  // namespace portico
