// The GGX (Trowbridge-Reitz) microfacet distribution, isotropic, in a local
// frame whose z axis is the surface normal; Smith's separable masking, and
// sampling of the normals visible from a direction (Heitz 2018), whose
// reflected directions have pdf D G1(wi) / (4 cos(wi)).
#pragma once

#include <algorithm>
#include <cmath>

#include "common/math.h"

namespace portico {

struct Ggx {
  float alpha = 0;

  float density(const Vec3& m) const {   // D(m)
    if (m.z <= 0) return 0;
    const float a2 = alpha * alpha;
    const float d = m.z * m.z * (a2 - 1.0f) + 1.0f;
    return a2 / (kPi * d * d);
  }
  // Smith's G1 of direction w over microfacet m (0 where w sees m's back).
  float masking(const Vec3& w, const Vec3& m) const {
    if (dot(w, m) * w.z <= 0) return 0;
    const float cos2 = w.z * w.z;
    if (cos2 >= 1.0f) return 1.0f;
    const float tan2 = (1.0f - cos2) / cos2;
    return 2.0f / (1.0f + std::sqrt(1.0f + alpha * alpha * tan2));
  }
  // A microfacet normal seen from wi (wi.z > 0), for u1, u2 uniform in [0,1).
  Vec3 sampleVisible(const Vec3& wi, float u1, float u2) const {
    const Vec3 stretched = normalize(Vec3(alpha * wi.x, alpha * wi.y, wi.z));
    const float lensq = stretched.x * stretched.x + stretched.y * stretched.y;
    const Vec3 t1 = lensq > 0 ? Vec3(-stretched.y, stretched.x, 0) / std::sqrt(lensq) : Vec3(1, 0, 0);
    const Vec3 t2 = cross(stretched, t1);
    const float r = std::sqrt(u1), phi = 2.0f * kPi * u2;
    const float p1 = r * std::cos(phi);
    const float s = 0.5f * (1.0f + stretched.z);
    const float p2 = (1.0f - s) * std::sqrt(std::max(0.0f, 1.0f - p1 * p1)) + s * r * std::sin(phi);
    const Vec3 n = t1 * p1 + t2 * p2 + stretched * std::sqrt(std::max(0.0f, 1.0f - p1 * p1 - p2 * p2));
    return normalize(Vec3(alpha * n.x, alpha * n.y, std::max(1e-7f, n.z)));
  }
  // The pdf (solid angle) of reflected direction wo when m is sampled from wi.
  float reflectedPdf(const Vec3& wi, const Vec3& wo) const {
    if (wi.z <= 0 || wo.z <= 0) return 0;
    const Vec3 m = normalize(wi + wo);
    return density(m) * masking(wi, m) / (4.0f * wi.z);
  }
};

}  // namespace portico
