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

LightSampler::LightSampler(const std::vector<AreaLight>& lights, std::vector<uint32_t> candidates)
    : candidates_(std::move(candidates)) {
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
    c.area = light.area();
    if (light.isPoint()) c.point = &light;
    prepared_.push_back(c);
  }
}

double LightSampler::weight(const Candidate& light, const Vec3& point, const Vec3& normal) {
  const Vec3 toPoint = point - light.center;
  if (light.point) {
    // Its light reaches the side of the point's tangent plane it lies on.
    const float d2 = dot(toPoint, toPoint);
    if (!(dot(normal, toPoint) < 0 && d2 > 0)) return 0;
    const float intensity = luminance(light.point->intensityToward(toPoint / std::sqrt(d2)));
    return intensity / std::max(double(d2), kNearestPointLight * kNearestPointLight);
  }
  // A point behind the light's plane sees only its dark back.
  const bool lightFacesPoint = dot(light.normal, toPoint) > 0;
  bool pointFacesLight = false;   // any part of the light above the point's tangent plane
  for (int k = 0; k < light.cornerCount; ++k) pointFacesLight |= dot(normal, light.corners[k] - point) > 0;
  if (!(lightFacesPoint && pointFacesLight)) return 0;
  const double d2 = std::max(double(dot(toPoint, toPoint)), double(light.reach) * light.reach);
  return light.luminousPower / d2;
}

LightChoice LightSampler::choose(const Vec3& point, const Vec3& normal, float u) const {
  thread_local std::vector<double> cumulative;
  cumulative.assign(candidates_.size(), 0.0);
  double total = 0;
  for (size_t i = 0; i < prepared_.size(); ++i) {
    total += weight(prepared_[i], point, normal);
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

float LightSampler::pdfAlong(const Vec3& point, const Vec3& normal, const Vec3& direction) const {
  // The nearest candidate area light the ray meets from its front.
  size_t nearest = prepared_.size();
  float nearestT = kInfinity, nearestCos = 0;
  for (size_t i = 0; i < prepared_.size(); ++i) {
    const Candidate& light = prepared_[i];
    if (light.point) continue;
    const float cosLight = -dot(light.normal, direction);
    if (cosLight <= 0) continue;
    const float t = dot(light.corners[0] - point, light.normal) / -cosLight;
    if (!(t > 0 && t < nearestT)) continue;
    // Where it meets the light's plane, in the light's (s, t) coordinates.
    const Vec3 offset = point + direction * t - light.corners[0];
    const Vec3 e1 = light.corners[1] - light.corners[0], e2 = light.corners[2] - light.corners[0];
    const float e11 = dot(e1, e1), e12 = dot(e1, e2), e22 = dot(e2, e2);
    const float o1 = dot(offset, e1), o2 = dot(offset, e2);
    const float det = e11 * e22 - e12 * e12;
    if (!(det > 0)) continue;
    const float s = (o1 * e22 - o2 * e12) / det, v = (o2 * e11 - o1 * e12) / det;
    const bool inside = light.cornerCount == 3 ? (s >= 0 && v >= 0 && s + v <= 1) : (s >= 0 && v >= 0 && s <= 1 && v <= 1);
    if (!inside) continue;
    nearest = i;
    nearestT = t;
    nearestCos = cosLight;
  }
  if (nearest == prepared_.size()) return 0;
  double total = 0;
  for (const Candidate& light : prepared_) total += weight(light, point, normal);
  if (!(total > 0)) return 0;
  const double chosen = weight(prepared_[nearest], point, normal) / total;
  // Area sampling: 1 / area, as solid angle d^2 / (cos area).
  return static_cast<float>(chosen * double(nearestT) * nearestT / (double(nearestCos) * prepared_[nearest].area));
}

}  // namespace portico
