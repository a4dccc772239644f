// The one ray-triangle test of portico: Woop, Benthin and Wald, "Watertight
// Ray/Triangle Intersection" (JCGT 2013), two-sided.
//
// Every accelerator calls this exact function and folds its results with
// closerThan(), so all of them return the identical Hit (same primitive, same
// t bit for bit): the result depends only on (ray, triangle), never on the
// order in which triangles are tested or on how far a search has got.
//
// Watertight: a ray that crosses a shared edge or vertex of a mesh hits at
// least one of the triangles sharing it. This holds because every vertex is
// transformed into the ray's frame by the same arithmetic whichever triangle
// it belongs to, and the edge functions are exactly antisymmetric, so two
// triangles sharing an edge see it with exactly opposite signs.
//
// Floating-point contraction (fused multiply-add) would break that
// antisymmetry, and could make two call sites of this function round
// differently: portico compiles with -ffp-contract=off and without
// -ffast-math (top-level CMakeLists.txt).
#pragma once

#include <cmath>
#include <cstdint>

#include "common/math.h"
#include "common/ray.h"

namespace portico {

// Per-ray constants of the test, computed once per ray: the ray is taken to
// a frame where it starts at the origin and runs along +z with unit speed.
// Names follow the paper: kz is the axis where the direction is largest in
// magnitude; kx, ky are the other two (swapped when the direction along kz
// is negative, to keep the triangles' winding); Sx, Sy shear the direction
// onto the kz axis and Sz scales it to length 1 there.
struct WatertightRay {
  int kx = 0, ky = 1, kz = 2;
  float Sx = 0, Sy = 0, Sz = 1;

  WatertightRay() = default;
  explicit WatertightRay(const Vec3& direction) {
    chooseAxes(direction);
    const float d[3] = {direction.x, direction.y, direction.z};
    Sx = d[kx] / d[kz];
    Sy = d[ky] / d[kz];
    Sz = 1.0f / d[kz];
  }

  // kx, ky and kz alone, for callers that compute the three quotients
  // themselves (the same correctly rounded divisions). Without branches:
  // random directions would mispredict them.
  void chooseAxes(const Vec3& direction) {
    const float ax = std::fabs(direction.x), ay = std::fabs(direction.y),
                az = std::fabs(direction.z);
    // Ties go to the lower axis, so the choice is a pure function of the direction.
    const int xLargest = int(ax >= ay) & int(ax >= az);
    const int yLargest = (1 - xLargest) & int(ay >= az);
    kz = 2 - 2 * xLargest - yLargest;
    // The two axes after kz, cyclically, as arithmetic and masks: GCC
    // compiles the plain conditionals into branches.
    const int next = (kz + 1) & -int(kz != 2), after = (next + 1) & -int(next != 2);
    const float d[3] = {direction.x, direction.y, direction.z};
    const int swap = (next ^ after) & -int(d[kz] < 0.0f);
    kx = next ^ swap;
    ky = after ^ swap;
  }
};

// Rays with non-finite origins or directions are never traced by any
// accelerator (they would make the triangle test meaningless).
inline bool hasFiniteOriginAndDirection(const Ray& ray) {
  return isFinite(ray.origin) && isFinite(ray.direction);
}

// Whether the triangle has zero area: the cross product of its edges,
// computed in double from the float vertices, is exactly zero. Exact for
// vertices whose coordinates are within 2^29 of each other in magnitude
// (their differences are then exact in double).
inline bool isDegenerateTriangle(const Vec3& v0, const Vec3& v1, const Vec3& v2) {
  const double ax = double(v1.x) - v0.x, ay = double(v1.y) - v0.y, az = double(v1.z) - v0.z;
  const double bx = double(v2.x) - v0.x, by = double(v2.y) - v0.y, bz = double(v2.z) - v0.z;
  return ay * bz == az * by && az * bx == ax * bz && ax * by == ay * bx;
}

// Whether the ray hits triangle (v0, v1, v2) at some t with
// ray.tMin < t < ray.tMax. On a hit, t is set, and u, v are the barycentric
// weights of v1 and v2 (the hit point is (1-u-v)*v0 + u*v1 + v*v2).
// Degenerate triangles (zero area, see isDegenerateTriangle) and rays lying
// in the triangle's plane never hit.
inline bool intersectTriangle(const WatertightRay& frame, const Ray& ray, const Vec3& v0,
                              const Vec3& v1, const Vec3& v2, float& t, float& u, float& v) {
  // Vertices relative to the ray origin. Arrays rather than Vec3::operator[]
  // so that the per-ray axis indices become plain indexed loads.
  const Vec3 a = v0 - ray.origin, b = v1 - ray.origin, c = v2 - ray.origin;
  const float A[3] = {a.x, a.y, a.z};
  const float B[3] = {b.x, b.y, b.z};
  const float C[3] = {c.x, c.y, c.z};

  // Shear the vertices into the ray's frame (the ray becomes the +z axis).
  const float Ax = A[frame.kx] - frame.Sx * A[frame.kz];
  const float Ay = A[frame.ky] - frame.Sy * A[frame.kz];
  const float Bx = B[frame.kx] - frame.Sx * B[frame.kz];
  const float By = B[frame.ky] - frame.Sy * B[frame.kz];
  const float Cx = C[frame.kx] - frame.Sx * C[frame.kz];
  const float Cy = C[frame.ky] - frame.Sy * C[frame.kz];

  // Edge functions: twice the signed areas of the triangles (ray, edge); U
  // belongs to the edge opposite v0, so it is v0's (unnormalised) weight.
  float U = Cx * By - Cy * Bx;
  float V = Ax * Cy - Ay * Cx;
  float W = Bx * Ay - By * Ax;

  // An exact zero in single precision may be a rounding artefact of a ray
  // passing very close to an edge: decide it in double precision, where the
  // products of two floats are exact.
  if (U == 0.0f || V == 0.0f || W == 0.0f) {
    const double CxBy = double(Cx) * double(By), CyBx = double(Cy) * double(Bx);
    const double AxCy = double(Ax) * double(Cy), AyCx = double(Ay) * double(Cx);
    const double BxAy = double(Bx) * double(Ay), ByAx = double(By) * double(Ax);
    U = float(CxBy - CyBx);
    V = float(AxCy - AyCx);
    W = float(BxAy - ByAx);
  }

  // Two-sided: the ray passes inside when all three have the same sign
  // (zeros count as either: the ray touches an edge or a vertex).
  if ((U < 0.0f || V < 0.0f || W < 0.0f) && (U > 0.0f || V > 0.0f || W > 0.0f)) return false;

  // det == 0: the ray lies in the triangle's plane, or the triangle is degenerate.
  const float det = U + V + W;
  if (det == 0.0f) return false;

  // Scaled z coordinates and the scaled hit distance T = t * det.
  const float Az = frame.Sz * A[frame.kz];
  const float Bz = frame.Sz * B[frame.kz];
  const float Cz = frame.Sz * C[frame.kz];
  const float T = U * Az + V * Bz + W * Cz;

  // Range check before dividing: tMin < T/det < tMax, i.e.
  // tMin*|det| < T*sign(det) < tMax*|det|. Done in double, where the
  // products of two floats are exact, so this never rejects a hit that the
  // check after the division would accept. Written as "accept only if" so
  // that NaNs (from non-finite input) are rejected.
  const double signedT = det > 0.0f ? double(T) : -double(T);
  const double absDet = std::fabs(double(det));
  if (!(signedT > double(ray.tMin) * absDet && signedT < double(ray.tMax) * absDet)) return false;

  // One correctly rounded division each: t may round onto a bound, so check again.
  const float hitT = T / det;
  if (!(hitT > ray.tMin && hitT < ray.tMax)) return false;

  // A zero-area triangle (collinear vertices) can pass the tests above by
  // rounding. Checked only here, on the rare accepted hits, so it costs
  // nothing on the common misses: exactly zero in double when the triangle
  // is exactly degenerate (equal products of exact differences round alike).
  if (isDegenerateTriangle(v0, v1, v2)) return false;
  t = hitT;
  u = V / det;
  v = W / det;
  return true;
}

}  // namespace portico
