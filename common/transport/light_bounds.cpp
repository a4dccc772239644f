#include "common/transport/light_bounds.h"

#include <algorithm>
#include <cmath>

namespace portico {
namespace {

// Rounding must never make a group that can light a point look dark: the
// cone around two cones is widened by this angle (radians) and a group is
// dark only when its best cosines are this far past the limit.
constexpr float kConeSlack = 1e-3f;
constexpr float kCosineSlack = 1e-3f;

float clampedAcos(float c) { return std::acos(std::clamp(c, -1.0f, 1.0f)); }
float sineOf(float cosine) { return std::sqrt(std::max(0.0f, 1.0f - cosine * cosine)); }

// cos(max(0, a - b)) and sin(max(0, a - b)) from the sines and cosines of
// angles a, b in [0, pi]: no acos per node at every shading point.
float cosOfClampedDifference(float sinA, float cosA, float sinB, float cosB) {
  return cosA > cosB ? 1.0f : cosA * cosB + sinA * sinB;
}
float sinOfClampedDifference(float sinA, float cosA, float sinB, float cosB) {
  return cosA > cosB ? 0.0f : sinA * cosB - cosA * sinB;
}

// `v` turned by `angle` about unit `k` perpendicular to it (Rodrigues).
Vec3 rotatedAbout(const Vec3& v, const Vec3& k, float angle) {
  return v * std::cos(angle) + cross(k, v) * std::sin(angle);
}

}  // namespace

LightBounds unite(const LightBounds& a, const LightBounds& b) {
  if (a.box.empty()) return b;
  if (b.box.empty()) return a;
  LightBounds united;
  united.box = a.box;
  united.box.extend(b.box);
  united.power = a.power + b.power;
  united.cosEmission = std::min(a.cosEmission, b.cosEmission);
  const float spreadA = clampedAcos(a.cosSpread), spreadB = clampedAcos(b.cosSpread);
  // The angle between the axes, accurate for nearly parallel ones too.
  const float between = 2.0f * std::asin(std::min(1.0f, 0.5f * length(a.axis - b.axis)));
  if (std::min(between + spreadB, kPi) <= spreadA) {
    united.axis = a.axis, united.cosSpread = a.cosSpread;
    return united;
  }
  if (std::min(between + spreadA, kPi) <= spreadB) {
    united.axis = b.axis, united.cosSpread = b.cosSpread;
    return united;
  }
  // The smallest cone around both: half the angle from A's far edge to B's.
  const float spread = 0.5f * (spreadA + between + spreadB) + kConeSlack;
  const Vec3 turn = cross(a.axis, b.axis);
  if (spread >= kPi || !(dot(turn, turn) > 1e-12f)) {
    united.axis = a.axis, united.cosSpread = -1.0f;   // the whole sphere
    return united;
  }
  united.axis = normalize(rotatedAbout(a.axis, normalize(turn), spread - kConeSlack - spreadA));
  united.cosSpread = std::cos(spread);
  return united;
}

PreparedLightBounds prepare(const LightBounds& bounds) {
  PreparedLightBounds p;
  p.power = bounds.power > 0 ? bounds.power : 0.0f;
  p.center = bounds.box.center();
  p.half = bounds.box.diagonal() * 0.5f;
  // The sphere around the box, a little larger so that rounding keeps it around.
  p.radius = length(p.half) * (1.0f + 1e-4f) + 1e-6f;
  p.axis = bounds.axis;
  p.cosSpread = bounds.cosSpread;
  p.sinSpread = sineOf(bounds.cosSpread);
  p.cosEmission = bounds.cosEmission;
  // 2 sin(theta_o / 2), or < 0 where the half-space test does not apply.
  p.tilt = bounds.cosEmission >= 0.0f && bounds.cosSpread > 0.0f
               ? std::sqrt(std::max(0.0f, 2.0f * (1.0f - bounds.cosSpread)))
               : -1.0f;
  return p;
}

float importance(const PreparedLightBounds& bounds, const Vec3& point, const Vec3& normal) {
  if (!(bounds.power > 0)) return 0.0f;
  const Vec3 toPoint = point - bounds.center;
  const float distance2 = dot(toPoint, toPoint);
  const float distance = std::sqrt(distance2);
  // Exact for the box, where the cosine bounds below are loose: a point
  // inside the sphere around a flat box of panels (the ceiling lights of the
  // floor below, a slab away) learns nothing from them. A box all below the
  // point's tangent plane cannot light its upper side; lights emitting at
  // most 90 degrees from normals n near the axis a light only points p with
  // dot(n, p - q) > 0 for a q in the box, and dot(n, v) <= dot(a, v) +
  // |n - a| |v|, |n - a| <= 2 sin(theta_o / 2).
  const float farthest = distance + bounds.radius;
  const float slack = kCosineSlack * (farthest + 1.0f);
  const Vec3& h = bounds.half;
  // The largest dot(d, q - point) over the box's points q.
  const auto reachAlong = [&](const Vec3& d) {
    return -dot(d, toPoint) + std::abs(d.x) * h.x + std::abs(d.y) * h.y + std::abs(d.z) * h.z;
  };
  if (reachAlong(normal) <= -slack) return 0.0f;
  if (bounds.tilt >= 0.0f && reachAlong(-bounds.axis) + bounds.tilt * farthest <= -slack) return 0.0f;
  const float radius2 = bounds.radius * bounds.radius;
  // theta_b: the half angle the sphere spans from the point (pi from inside).
  float sinBox = 0.0f, cosBox = -1.0f;
  if (distance2 > radius2) {
    sinBox = bounds.radius / distance;
    cosBox = std::sqrt(std::max(0.0f, 1.0f - sinBox * sinBox));
  }
  const Vec3 toPointUnit = distance > 0 ? toPoint / distance : Vec3(0.0f);
  // The smallest angle between an emitting normal and a direction from the
  // box to the point: theta_w - theta_o - theta_b, clamped at 0.
  const float cosAxis = dot(bounds.axis, toPointUnit), sinAxis = sineOf(cosAxis);
  const float cosOutside = cosOfClampedDifference(sinAxis, cosAxis, bounds.sinSpread, bounds.cosSpread);
  const float sinOutside = sinOfClampedDifference(sinAxis, cosAxis, bounds.sinSpread, bounds.cosSpread);
  const float cosEmitted = cosOfClampedDifference(sinOutside, cosOutside, sinBox, cosBox);
  if (cosEmitted < bounds.cosEmission - kCosineSlack) return 0.0f;
  // The smallest angle between the point's normal and a direction to the box.
  const float cosNormal = -dot(normal, toPointUnit), sinNormal = sineOf(cosNormal);
  const float cosReceived = cosOfClampedDifference(sinNormal, cosNormal, sinBox, cosBox);
  if (cosReceived < -kCosineSlack) return 0.0f;
  // Cosines clamped above 0: a group that may light the point keeps a weight.
  return bounds.power * std::max(cosEmitted, kCosineSlack) * std::max(cosReceived, kCosineSlack) /
         std::max(distance2, radius2);
}

double groupCost(const LightBounds& bounds, const Bounds3& parentBox, int axis) {
  if (bounds.box.empty()) return 0.0;
  const double spread = std::acos(std::clamp(double(bounds.cosSpread), -1.0, 1.0));
  const double emission = std::acos(std::clamp(double(bounds.cosEmission), -1.0, 1.0));
  const double reach = std::min(spread + emission, double(kPi));
  const double sinSpread = std::sin(spread), cosSpread = std::cos(spread);
  // M_Omega: the cone's solid angle weighted by the emission cosine.
  const double orientation = 2 * kPi * (1 - cosSpread) + kPi / 2 * (2 * reach * sinSpread - std::cos(spread - 2 * reach) -
                                                                    2 * spread * sinSpread + cosSpread);
  // A box of lights on one point or one line still has some extent (1 cm).
  const Vec3 d = bounds.box.diagonal() + Vec3(0.01f);
  const double area = 2.0 * (double(d.x) * d.y + double(d.y) * d.z + double(d.z) * d.x);
  const Vec3 parent = parentBox.diagonal();
  const double stretch = parent[axis] > 0 ? maxComponent(parent) / parent[axis] : 1.0;
  return bounds.power * orientation * area * stretch;
}

}  // namespace portico
