#include "common/transport/light_sampler.h"

#include <algorithm>
#include <unordered_set>

#include "common/transport/sampling.h"

namespace portico {

std::vector<uint32_t> LightSampler::allLights(const std::vector<AreaLight>& lights) {
  std::vector<uint32_t> ids(lights.size());
  for (size_t i = 0; i < lights.size(); ++i) ids[i] = static_cast<uint32_t>(i);
  return ids;
}

namespace {

// A point luminaire's weight stops growing this near it (metres): a point
// almost at the lamp does not take every sample.
constexpr double kNearestPointLight = 0.01;

// The cells within `hops` portals of `cell` (itself included), breadth first
// over the store's neighbour index: a tower's 35 K portals are not looked at
// per lease.
std::unordered_set<uint32_t> cellsWithin(const SceneStore& scene, uint32_t cell, int hops) {
  std::unordered_set<uint32_t> reached{cell};
  std::vector<uint32_t> frontier{cell};
  for (int step = 0; step < hops; ++step) {
    std::vector<uint32_t> next;
    for (uint32_t c : frontier)
      for (uint32_t n : scene.neighboursOf(c))
        if (reached.insert(n).second) next.push_back(n);
    frontier.swap(next);
  }
  return reached;
}

}  // namespace

std::vector<bool> LightSampler::cellsNear(const SceneStore& scene, uint32_t cell, int hops) {
  const size_t cellCount = scene.cells().size();
  if (hops < 0) return std::vector<bool>(cellCount, true);
  std::vector<bool> near(cellCount, false);
  if (cell >= cellCount) return near;
  for (uint32_t c : cellsWithin(scene, cell, hops)) near[c] = true;
  return near;
}

std::vector<uint32_t> LightSampler::lightsNear(const SceneStore& scene, uint32_t cell, int hops) {
  if (hops < 0) return allLights(scene.lights());
  if (cell >= scene.cells().size()) return {};
  std::vector<uint32_t> ids;
  for (uint32_t c : cellsWithin(scene, cell, hops))
    ids.insert(ids.end(), scene.lightsOf(c).begin(), scene.lightsOf(c).end());
  std::sort(ids.begin(), ids.end());   // in light order, as the sampler's draws expect
  return ids;
}

LightSampler::LightSampler(const std::vector<AreaLight>& lights, std::vector<uint32_t> candidates,
                           LightSampling sampling)
    : candidates_(std::move(candidates)) {
  if (sampling == LightSampling::Tree) {
    tree_.emplace(lights, candidates_);
    return;
  }
  prepared_.reserve(candidates_.size());
  for (uint32_t id : candidates_) {
    const AreaLight& light = lights[id];
    Candidate c;
    c.center = light.center();
    c.normal = light.normal();
    c.cornerCount = light.corners(c.corners);
    // How far the light reaches from its centre: a point cannot be nearer
    // the light than that without being over it, so the falloff is capped
    // there.
    c.reach = 0.5f * length(light.edge1 + light.edge2);
    if (light.isTriangle()) {
      c.reach = 0.0f;
      for (int k = 0; k < c.cornerCount; ++k) c.reach = std::max(c.reach, length(c.corners[k] - c.center));
    }
    c.luminousPower = luminance(light.power());
    if (light.isPoint()) c.point = &light;
    prepared_.push_back(c);
  }
}

LightChoice LightSampler::choose(const Vec3& point, const Vec3& normal, float u) const {
  return tree_ ? tree_->choose(point, normal, u) : scan(point, normal, u);
}

LightChoice LightSampler::scan(const Vec3& point, const Vec3& normal, float u) const {
  thread_local std::vector<double> cumulative;
  cumulative.assign(candidates_.size(), 0.0);
  double total = 0;
  for (size_t i = 0; i < prepared_.size(); ++i) {
    const Candidate& light = prepared_[i];
    const Vec3 toPoint = point - light.center;
    if (light.point) {
      // Its light reaches the side of the point's tangent plane it lies on.
      const float d2 = dot(toPoint, toPoint);
      if (dot(normal, toPoint) < 0 && d2 > 0) {
        const float intensity = luminance(light.point->intensityToward(toPoint / std::sqrt(d2)));
        total += intensity / std::max(double(d2), kNearestPointLight * kNearestPointLight);
      }
      cumulative[i] = total;
      continue;
    }
    // A point behind the light's plane sees only its dark back.
    const bool lightFacesPoint = dot(light.normal, toPoint) > 0;
    bool pointFacesLight = false;   // any part of the light above the point's tangent plane
    for (int k = 0; k < light.cornerCount; ++k) pointFacesLight |= dot(normal, light.corners[k] - point) > 0;
    if (lightFacesPoint && pointFacesLight) {
      const double d2 = std::max(double(dot(toPoint, toPoint)), double(light.reach) * light.reach);
      total += light.luminousPower / d2;
    }
    cumulative[i] = total;
  }
  if (!(total > 0)) return {};
  const double target = u * total;
  size_t chosen = 0;
  while (chosen + 1 < candidates_.size() && cumulative[chosen] <= target) ++chosen;
  // The first entry whose running total exceeds target has nonzero weight.
  const double previous = chosen ? cumulative[chosen - 1] : 0.0;
  return {candidates_[chosen], static_cast<float>((cumulative[chosen] - previous) / total)};
}

}  // namespace portico
