#include "common/transport/cell_portals.h"

#include "common/accel/triangle_intersect.h"

#include <algorithm>
#include <cmath>
#include <optional>

namespace portico {

namespace {
constexpr float kPortalSlack = 1e-4f;   // metres
// Twice offsetAlongNormal's relative offset of a bounce (sampling.h).
constexpr float kBounceReach = 4e-5f;
// The most grazing exit for which a portal behind the origin is looked for.
constexpr float kMinLeavingCosine = 1.0f / 1024.0f;
// Growth of a box, relative to the largest coordinate involved, that lies
// far beyond the triangle test's rounding: 2^-16, 256 float ulps.
constexpr float kRelativeReach = 1.0f / 65536.0f;

float largestMagnitude(const Vec3& p) { return std::max(std::abs(p.x), std::max(std::abs(p.y), std::abs(p.z))); }

Bounds3 grown(Bounds3 box, float by) {
  box.lo = box.lo - Vec3(by);
  box.hi = box.hi + Vec3(by);
  return box;
}
}  // namespace

CellPortals::CellPortals(const std::vector<CellPortalView>& portals, const Vec3& cellCenter) {
  for (const CellPortalView& portal : portals) {
    if (portal.polygon.size() < 3) continue;
    Vec3 centroid(0);
    for (const Vec3& p : portal.polygon) centroid += p;
    centroid = centroid / float(portal.polygon.size());
    // Newell's normal: robust for any planar polygon.
    Vec3 normal(0);
    for (size_t i = 0; i < portal.polygon.size(); ++i) {
      const Vec3& a = portal.polygon[i];
      const Vec3& b = portal.polygon[(i + 1) % portal.polygon.size()];
      normal += cross(a, b);
    }
    if (!(length(normal) > 0)) continue;
    normal = normalize(normal);
    // Cells are convex regions (rooms, voxels): the outside of a portal is
    // the side away from the cell's centre.
    if (dot(normal, centroid - cellCenter) < 0) normal = -normal;
    Bounds3 bounds;
    for (const Vec3& p : portal.polygon) bounds.extend(p);
    polygons_.push_back({portal.polygon, normal, portal.neighborCell, bounds});
    for (size_t i = 1; i + 1 < portal.polygon.size(); ++i) {
      const Vec3 &v0 = portal.polygon[0], &v1 = portal.polygon[i], &v2 = portal.polygon[i + 1];
      Bounds3 box;
      box.extend(v0);
      box.extend(v1);
      box.extend(v2);
      const float magnitude = std::max(largestMagnitude(box.lo), largestMagnitude(box.hi));
      triangles_.push_back(
          {v0, v1, v2, normal, portal.neighborCell, grown(box, kPortalSlack + kRelativeReach * magnitude)});
    }
  }
}

namespace {

float distanceToSegment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const float len2 = dot(ab, ab);
  const float s = len2 > 0 ? std::clamp(dot(p - a, ab) / len2, 0.0f, 1.0f) : 0.0f;
  return length(p - (a + ab * s));
}

// Distance from p to a planar convex polygon with unit normal n.
float distanceToPolygon(const Vec3& p, const std::vector<Vec3>& polygon, const Vec3& n) {
  const float height = dot(p - polygon[0], n);
  const Vec3 projected = p - n * height;
  bool anyPositive = false, anyNegative = false;
  float edgeDistance = kInfinity;
  for (size_t i = 0; i < polygon.size(); ++i) {
    const Vec3& a = polygon[i];
    const Vec3& b = polygon[(i + 1) % polygon.size()];
    // Inside when the projected point is on the same side of every edge
    // (whichever way the polygon winds).
    const float side = dot(cross(b - a, projected - a), n);
    anyPositive |= side > 0;
    anyNegative |= side < 0;
    edgeDistance = std::min(edgeDistance, distanceToSegment(p, a, b));
  }
  if (!(anyPositive && anyNegative)) return std::abs(height);
  return edgeDistance;
}
}  // namespace

void CellPortals::neighborsNear(const Vec3& p, float radius, std::vector<uint32_t>& neighbors) const {
  neighbors.clear();
  // Every deposit asks; most lie far from every portal. The distance to a
  // polygon is at least the distance to its plane and to its bounding box:
  // reject on those first, with a margin far above rounding so that only
  // the exact distance below ever decides a near case.
  const float reject = radius * 1.001f + 1e-6f;
  for (const PortalPolygon& portal : polygons_) {
    if (p.x < portal.bounds.lo.x - reject || p.x > portal.bounds.hi.x + reject ||
        p.y < portal.bounds.lo.y - reject || p.y > portal.bounds.hi.y + reject ||
        p.z < portal.bounds.lo.z - reject || p.z > portal.bounds.hi.z + reject)
      continue;
    if (std::abs(dot(p - portal.points[0], portal.normal)) > reject) continue;
    if (distanceToPolygon(p, portal.points, portal.normal) > radius) continue;
    if (std::find(neighbors.begin(), neighbors.end(), portal.neighborCell) == neighbors.end())
      neighbors.push_back(portal.neighborCell);
  }
}

void CellPortals::leaveBy(const Ray& ray, CellEvent& event) const {
  if (triangles_.empty()) return;
  // Portals are few per cell: test them all. A ray leaves only through a
  // portal it moves out of, so a ray that just entered through a portal
  // never re-crosses it at t = 0.
  Ray limited = ray;
  limited.tMax = event.kind == CellEvent::Kind::Surface ? event.t : ray.tMax;
  // A ray starting on a portal's plane (a camera exactly on a voxel face)
  // and moving out must leave at t = 0, whatever the rounding of t: an
  // outward portal a hair behind the origin still counts. So does one
  // behind a bounce off a surface lying on the portal's plane: the bounce
  // starts offsetAlongNormal (2e-5 of the coordinates) beyond it, outside
  // the cell. "Behind" is measured across the portal's plane, so along a
  // ray leaving at a grazing angle it reaches further back (below).
  const float behind = std::max(kPortalSlack, kBounceReach * std::max(1.0f, largestMagnitude(ray.origin)));
  limited.tMin = std::min(ray.tMin, -behind / kMinLeavingCosine);
  // The box of the segment the portal test accepts hits on. The test is
  // backward stable: a point it reports (origin + t * direction, exactly)
  // lies within a few ulps of the triangle, measured in the magnitudes of
  // the coordinates involved; the segment's computed ends are as close to
  // the exact ones. So a hit is impossible unless the segment's box, grown
  // by 2^-16 of the ray's coordinates, meets the triangle's `reach` (grown
  // likewise by its own and by the slack). Skipping on that changes no
  // answer. An unbounded segment (no surface hit) skips nothing.
  Bounds3 segment{Vec3(-kInfinity), Vec3(kInfinity)};
  if (std::isfinite(limited.tMax)) {
    const Vec3 start = ray.origin + ray.direction * limited.tMin;
    const Vec3 end = ray.origin + ray.direction * limited.tMax;
    // The magnitudes before any cancellation in origin + t * direction.
    const float magnitude = largestMagnitude(ray.origin) +
                            largestMagnitude(ray.direction) * std::max(-limited.tMin, limited.tMax);
    segment = grown(Bounds3{min(start, end), max(start, end)}, kRelativeReach * magnitude);
  }
  // Made for the first portal that passes the box test (most rays: none).
  std::optional<WatertightRay> frame;
  for (const PortalTriangle& portal : triangles_) {
    if (segment.hi.x < portal.reach.lo.x || segment.lo.x > portal.reach.hi.x ||
        segment.hi.y < portal.reach.lo.y || segment.lo.y > portal.reach.hi.y ||
        segment.hi.z < portal.reach.lo.z || segment.lo.z > portal.reach.hi.z)
      continue;
    const float leaving = dot(ray.direction, portal.outward);
    if (leaving <= 0) continue;
    if (!frame) frame.emplace(ray.direction);
    Ray own = limited;
    own.tMin = std::min(ray.tMin, -behind / std::max(leaving, kMinLeavingCosine));
    float t, u, v;
    // Strictly nearer than the geometry: a wall at the same t wins.
    if (intersectTriangle(*frame, own, portal.v0, portal.v1, portal.v2, t, u, v) && t < limited.tMax) {
      limited.tMax = t;
      event.kind = CellEvent::Kind::Portal;
      event.t = t;
      event.primitive = kNoPrimitive;
      event.neighborCell = portal.neighborCell;
    }
  }
}

float tMinBeforePortal(const Ray& ray, float t) {
  const float magnitude = largestMagnitude(ray.origin) + t * largestMagnitude(ray.direction);
  return std::max(0.0f, t - magnitude / 65536.0f);
}

}  // namespace portico
