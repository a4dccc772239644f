#include "common/transport/light_sampler.h"

#include "common/transport/sampling.h"

namespace portico {

LightChoice LightSampler::choose(const Vec3& point, const Vec3& normal, float u) const {
  thread_local std::vector<double> cumulative;
  cumulative.assign(lights_.size(), 0.0);
  double total = 0;
  for (size_t i = 0; i < lights_.size(); ++i) {
    const AreaLight& light = lights_[i];
    const Vec3 toPoint = point - light.center();
    // A point behind the light's plane sees only its dark back.
    const bool lightFacesPoint = dot(light.normal(), toPoint) > 0;
    // Half the light's diagonal: a point cannot be nearer the light than
    // that bound says without being over it, so cap the falloff there.
    const float halfDiagonal = 0.5f * length(light.edge1 + light.edge2);
    const Vec3 corner = light.corner;
    bool pointFacesLight = false;   // any part of the light above the point's tangent plane
    for (const Vec3& q : {corner, corner + light.edge1, corner + light.edge2, corner + light.edge1 + light.edge2})
      pointFacesLight |= dot(normal, q - point) > 0;
    if (lightFacesPoint && pointFacesLight) {
      const double d2 = std::max(double(dot(toPoint, toPoint)), double(halfDiagonal) * halfDiagonal);
      total += luminance(light.power()) / d2;
    }
    cumulative[i] = total;
  }
  if (!(total > 0)) return {};
  const double target = u * total;
  size_t chosen = 0;
  while (chosen + 1 < lights_.size() && cumulative[chosen] <= target) ++chosen;
  // The first entry whose running total exceeds target has nonzero weight.
  const double previous = chosen ? cumulative[chosen - 1] : 0.0;
  return {static_cast<uint32_t>(chosen), static_cast<float>((cumulative[chosen] - previous) / total)};
}

}  // namespace portico
