#include "common/transport/daylight_openings.h"

#include <cmath>
#include <string_view>

#include "common/transport/sampling.h"
#include "common/transport/sun_disc.h"

namespace portico {

bool isOutdoorCell(const std::string& name) {
  if (name == "outside" || name == "sky") return true;
  for (std::string_view prefix : {"outside-", "sky-", "facade-"})
    if (name.rfind(prefix, 0) == 0) return true;
  return false;
}

namespace {
// The light over points a, a + e1, a + e2 (and a + e1 + e2 for a
// parallelogram), turned so that it faces `indoors`.
AreaLight openingLight(uint32_t cell, LightShape shape, const Vec3& a, Vec3 e1, Vec3 e2, const Vec3& indoors) {
  if (dot(cross(e1, e2), indoors) < 0) std::swap(e1, e2);
  AreaLight light;
  light.cell = cell;
  light.shape = shape;
  light.corner = a;
  light.edge1 = e1;
  light.edge2 = e2;
  return light;
}
}  // namespace

std::vector<AreaLight> daylightOpenings(const SceneStore& scene, std::vector<uint32_t>* outdoorCells) {
  std::vector<AreaLight> openings;
  const auto& cells = scene.cells();
  for (const Portal& portal : scene.portals()) {
    if (portal.cellA >= cells.size() || portal.cellB >= cells.size() || portal.polygon.size() < 3) continue;
    const bool outdoorA = isOutdoorCell(cells[portal.cellA].name), outdoorB = isOutdoorCell(cells[portal.cellB].name);
    if (outdoorA == outdoorB) continue;
    const uint32_t indoor = outdoorA ? portal.cellB : portal.cellA;
    const std::vector<Vec3>& p = portal.polygon;
    Vec3 centre;
    for (const Vec3& v : p) centre += v;
    centre = centre / float(p.size());
    const Vec3 indoors = cells[indoor].bounds.center() - centre;
    // A parallelogram is one light; any other convex polygon a fan of triangles.
    const Vec3 e1 = p[1] - p[0], e2 = p.size() == 4 ? p[3] - p[0] : Vec3(0);
    const float size = length(e1) + length(e2);
    if (p.size() == 4 && length(p[0] + e1 + e2 - p[2]) <= 1e-5f * size) {
      openings.push_back(openingLight(indoor, LightShape::Parallelogram, p[0], e1, e2, indoors));
    } else {
      for (size_t k = 1; k + 1 < p.size(); ++k)
        openings.push_back(openingLight(indoor, LightShape::Triangle, p[0], p[k] - p[0], p[k + 1] - p[0], indoors));
    }
    if (outdoorCells) outdoorCells->resize(openings.size(), outdoorA ? portal.cellA : portal.cellB);
  }
  for (size_t k = 0; k < openings.size(); ++k) openings[k].id = static_cast<uint32_t>(k);
  return openings;
}

DaylightEmitters::DaylightEmitters(const SceneStore& scene, const DaylightSettings& settings)
    : sky_(settings) {
  openings_ = daylightOpenings(scene, &outdoorCells_);
}

Vec3 DaylightEmitters::power(size_t emitter) const {
  const AreaLight& opening = openings_[emitter % openings_.size()];
  const Vec3 outward = -opening.normal();
  if (emitter < openings_.size()) return sky_.irradianceFacing(outward) * opening.area();
  if (!sky_.hasSun()) return Vec3(0);
  const float cosine = dot(outward, sky_.sunDirection());
  return cosine > 0 ? sky_.sunIrradiance() * (cosine * opening.area()) : Vec3(0);
}

RayState DaylightEmitters::emitPhoton(size_t emitter, uint64_t photonsOfEmitter, uint64_t seed, uint64_t path) const {
  const AreaLight& opening = openings_[emitter % openings_.size()];
  const Vec3 inward = opening.normal();
  const float u = randomUniform(seed, RandomStream::Photon, path, 0, dim::LightU);
  const float v = randomUniform(seed, RandomStream::Photon, path, 0, dim::LightV);
  RayState photon;
  photon.kind = RayKind::Photon;
  photon.pathId = path;
  photon.origin = offsetAlongNormal(opening.pointAt(u, v), inward);
  const float share = float(photonsOfEmitter);
  if (emitter < openings_.size()) {
    photon.direction = sampleCosineHemisphere(inward, randomUniform(seed, RandomStream::Photon, path, 0, dim::DirectionU),
                                              randomUniform(seed, RandomStream::Photon, path, 0, dim::DirectionV));
    // pdf cos / pi over the hemisphere, uniform over the area: each photon
    // carries L pi A / N of the sky's light.
    photon.weight = sky_.radiance(-photon.direction) * (kPi * opening.area() / share);
  } else {
    photon.direction = -sampleSunDisc(sky_.sunDirection(), randomUniform(seed, RandomStream::Photon, path, 0, dim::DirectionU),
                                      randomUniform(seed, RandomStream::Photon, path, 0, dim::DirectionV));
    photon.weight = power(emitter) / share;
  }
  return photon;
}

std::optional<float> DaylightEmitters::distanceThrough(const AreaLight& opening, const Vec3& origin,
                                                       const Vec3& direction) {
  const Vec3 n = cross(opening.edge1, opening.edge2);
  const float denominator = dot(n, direction);
  if (denominator == 0.0f) return std::nullopt;
  const float t = dot(n, opening.corner - origin) / denominator;
  if (!(t > 0)) return std::nullopt;
  // The hit's coordinates along the edges, from the dual basis.
  const Vec3 d = origin + direction * t - opening.corner;
  const float nn = dot(n, n);
  const float s = dot(cross(d, opening.edge2), n) / nn;
  const float r = dot(cross(opening.edge1, d), n) / nn;
  const bool inside = opening.isTriangle() ? s >= 0 && r >= 0 && s + r <= 1 : s >= 0 && r >= 0 && s <= 1 && r <= 1;
  if (!inside) return std::nullopt;
  return t;
}

}  // namespace portico
