#include "common/transport/light_tree.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "common/photometry/luminous_intensity.h"
#include "common/transport/sampling.h"

namespace portico {
namespace {

// Buckets per axis when splitting a node (pbrt-v4 uses 12 as well): the
// build is linear per level, and finer buckets gain little.
constexpr int kBuckets = 12;
// A point luminaire's weight stops growing this near it (metres), as in the scan.
constexpr double kNearestPointLight = 0.01;

// The largest angle from the nadir (radians) at which a luminaire's file
// gives any light: the grid is linear between its angles and 0 outside
// them, and portico reads it at the middle of half-degree cells, so one
// degree past the last nonzero angle's neighbour bounds it.
float widestAngle(const LuminousIntensity& intensity) {
  const CandelaGrid& grid = intensity.grid();
  const size_t rows = grid.vertical.size();
  size_t lastLit = 0;
  bool lit = false;
  for (size_t h = 0; h < grid.horizontal.size(); ++h)
    for (size_t v = 0; v < rows; ++v)
      if (grid.candela[h * rows + v] > 0) lastLit = std::max(lastLit, v), lit = true;
  if (!lit) return kPi;
  const double degrees = (lastLit + 1 < rows ? grid.vertical[lastLit + 1] : grid.vertical[lastLit]) + 1.0;
  return degrees >= 180.0 ? kPi : float(degrees * kPi / 180.0);
}

}  // namespace

LightBounds LightTree::boundsOf(const AreaLight& light) {
  LightBounds bounds;
  bounds.power = luminance(light.power());
  if (!(bounds.power > 0)) bounds.power = 0;
  if (light.isPoint()) {
    bounds.box.extend(light.corner);
    bounds.axis = normalize(light.edge1);   // the nadir
    const float widest = widestAngle(*light.intensity);
    bounds.cosSpread = widest >= kPi ? -1.0f : std::cos(widest);
    bounds.cosEmission = 1.0f;   // it emits along the directions of its cone only
    return bounds;
  }
  Vec3 corners[4];
  const int count = light.corners(corners);
  for (int k = 0; k < count; ++k) bounds.box.extend(corners[k]);
  bounds.axis = light.normal();
  bounds.cosSpread = 1.0f;
  bounds.cosEmission = 0.0f;   // one-sided, up to 90 degrees from its normal
  return bounds;
}

LightTree::LightTree(const std::vector<AreaLight>& lights, std::vector<uint32_t> candidates) {
  std::sort(candidates.begin(), candidates.end());   // the build's order, whatever the caller's
  for (uint32_t id : candidates) {
    const AreaLight& light = lights[id];
    LightBounds bounds = boundsOf(light);
    if (!(bounds.power > 0) || !std::isfinite(bounds.power)) continue;
    Leaf leaf;
    leaf.light = id;
    leaf.center = light.center();
    leaf.normal = light.normal();
    if (light.isPoint())
      leaf.point = &light;
    else
      leaf.cornerCount = light.corners(leaf.corners);
    leaves_.push_back(leaf);
    leafBounds_.push_back(bounds);
  }
  if (leaves_.empty()) return;
  leafNodes_.resize(leaves_.size());
  nodes_.reserve(2 * leaves_.size() - 1);
  parents_.reserve(2 * leaves_.size() - 1);
  std::vector<uint32_t> order(leaves_.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<uint32_t>(i);
  build(order, 0, order.size(), 0, 0);
  for (Node& node : nodes_) node.prepared = prepare(node.bounds);
}

uint32_t LightTree::build(std::vector<uint32_t>& order, size_t begin, size_t end, uint32_t parent, uint32_t level) {
  const uint32_t index = static_cast<uint32_t>(nodes_.size());
  nodes_.emplace_back();
  parents_.push_back(parent);
  if (end - begin == 1) {
    nodes_[index].leaf = order[begin];
    nodes_[index].bounds = leafBounds_[order[begin]];
    leafNodes_[order[begin]] = index;
    depth_ = std::max(depth_, level);
    return index;
  }
  LightBounds all;
  Bounds3 centres;
  for (size_t i = begin; i < end; ++i) {
    all = unite(all, leafBounds_[order[i]]);
    centres.extend(leafBounds_[order[i]].box.center());
  }
  // The split of least cost over the buckets of each axis.
  double bestCost = std::numeric_limits<double>::infinity();
  int bestAxis = -1, bestBucket = 0;
  const Vec3 extent = centres.diagonal();
  auto bucketOf = [&](uint32_t leaf, int axis) {
    const float offset = (leafBounds_[leaf].box.center()[axis] - centres.lo[axis]) / extent[axis];
    return std::clamp(int(offset * kBuckets), 0, kBuckets - 1);
  };
  for (int axis = 0; axis < 3; ++axis) {
    if (!(extent[axis] > 0)) continue;
    std::array<LightBounds, kBuckets> buckets;
    for (size_t i = begin; i < end; ++i) {
      LightBounds& bucket = buckets[bucketOf(order[i], axis)];
      bucket = unite(bucket, leafBounds_[order[i]]);
    }
    // Costs of the groups below and above each split, by two sweeps.
    std::array<double, kBuckets> below{}, above{};
    LightBounds running;
    for (int b = 0; b < kBuckets; ++b) {
      running = unite(running, buckets[b]);
      below[b] = running.box.empty() ? -1.0 : groupCost(running, all.box, axis);
    }
    running = LightBounds{};
    for (int b = kBuckets - 1; b > 0; --b) {
      running = unite(running, buckets[b]);
      above[b] = running.box.empty() ? -1.0 : groupCost(running, all.box, axis);
    }
    for (int split = 0; split + 1 < kBuckets; ++split) {
      if (below[split] < 0 || above[split + 1] < 0) continue;   // one side empty
      const double cost = below[split] + above[split + 1];
      if (cost < bestCost) bestCost = cost, bestAxis = axis, bestBucket = split;
    }
  }
  size_t middle = begin + (end - begin) / 2;   // lights on one point: halves in candidate order
  if (bestAxis >= 0) {
    const auto cut = std::stable_partition(order.begin() + long(begin), order.begin() + long(end),
                                           [&](uint32_t leaf) { return bucketOf(leaf, bestAxis) <= bestBucket; });
    middle = size_t(cut - order.begin());
    if (middle == begin || middle == end) middle = begin + (end - begin) / 2;
  }
  build(order, begin, middle, index, level + 1);
  const uint32_t second = build(order, middle, end, index, level + 1);
  nodes_[index].secondChild = second;
  nodes_[index].bounds = unite(nodes_[index + 1].bounds, nodes_[second].bounds);
  return index;
}

float LightTree::leafImportance(const Node& node, const Vec3& point, const Vec3& normal) const {
  const Leaf& leaf = leaves_[node.leaf];
  const Vec3 toPoint = point - leaf.center;
  if (leaf.point) {
    // Its light reaches the side of the point's tangent plane it lies on,
    // as much as its intensity towards the point (4 pi I: the power of a
    // lamp sending I everywhere, the scale of the nodes' power).
    const float d2 = dot(toPoint, toPoint);
    const float cosReceived = -dot(normal, toPoint);
    if (!(cosReceived > 0 && d2 > 0)) return 0.0f;
    const float distance = std::sqrt(d2);
    const float intensity = luminance(leaf.point->intensityToward(toPoint / distance));
    if (!(intensity > 0)) return 0.0f;
    return float(4.0 * kPi * intensity * (cosReceived / distance) /
                 std::max(double(d2), kNearestPointLight * kNearestPointLight));
  }
  // A point behind the light's plane sees only its dark back; a light all
  // below the point's tangent plane cannot reach its upper side.
  if (!(dot(leaf.normal, toPoint) > 0)) return 0.0f;
  bool pointFacesLight = false;
  for (int k = 0; k < leaf.cornerCount; ++k) pointFacesLight |= dot(normal, leaf.corners[k] - point) > 0;
  if (!pointFacesLight) return 0.0f;
  return importance(node.prepared, point, normal);
}

float LightTree::nodeImportance(uint32_t index, const Vec3& point, const Vec3& normal) const {
  const Node& node = nodes_[index];
  return node.leaf == kInterior ? importance(node.prepared, point, normal) : leafImportance(node, point, normal);
}

LightChoice LightTree::choose(const Vec3& point, const Vec3& normal, float u) const {
  if (nodes_.empty()) return {};
  uint32_t index = 0;
  double probability = 1.0, rest = u;
  while (nodes_[index].leaf == kInterior) {
    const uint32_t first = index + 1, second = nodes_[index].secondChild;
    const double a = nodeImportance(first, point, normal), b = nodeImportance(second, point, normal);
    if (!(a > 0) && !(b > 0)) return {};   // nothing under this node reaches the point after all
    const double pFirst = a / (a + b);
    if (rest < pFirst) {
      index = first, probability *= pFirst, rest /= pFirst;
    } else {
      index = second, probability *= 1.0 - pFirst, rest = (rest - pFirst) / (1.0 - pFirst);
    }
    // Reused for the next choice: keep it in [0, 1) against rounding.
    rest = std::min(rest, std::nextafter(1.0, 0.0));
  }
  if (index == 0 && !(leafImportance(nodes_[0], point, normal) > 0)) return {};   // one light, dark here
  return {leaves_[nodes_[index].leaf].light, float(probability)};
}

double LightTree::probability(const Vec3& point, const Vec3& normal, uint32_t light) const {
  const auto found = std::lower_bound(leaves_.begin(), leaves_.end(), light,
                                      [](const Leaf& leaf, uint32_t id) { return leaf.light < id; });
  if (found == leaves_.end() || found->light != light) return 0.0;
  uint32_t index = leafNodes_[size_t(found - leaves_.begin())];
  if (index == 0) return leafImportance(nodes_[0], point, normal) > 0 ? 1.0 : 0.0;
  double probability = 1.0;
  while (index != 0) {
    const uint32_t parent = parents_[index];
    const uint32_t first = parent + 1, second = nodes_[parent].secondChild;
    const double a = nodeImportance(first, point, normal), b = nodeImportance(second, point, normal);
    if (!(a > 0) && !(b > 0)) return 0.0;
    probability *= (index == first ? a : b) / (a + b);
    index = parent;
  }
  return probability;
}

}  // namespace portico
