#include "common/accel/triangle_intersect.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <utility>
#include <vector>

namespace portico {
namespace {

struct Triangle {
  Vec3 v0, v1, v2;
};

bool hits(const Ray& ray, const Triangle& triangle, float& t, float& u, float& v) {
  const WatertightRay frame(ray.direction);
  return intersectTriangle(frame, ray, triangle.v0, triangle.v1, triangle.v2, t, u, v);
}

bool hits(const Ray& ray, const Triangle& triangle) {
  float t, u, v;
  return hits(ray, triangle, t, u, v);
}

int countHits(const Ray& ray, const std::vector<Triangle>& triangles) {
  int count = 0;
  for (const Triangle& triangle : triangles) count += hits(ray, triangle);
  return count;
}

Vec3 lerp(const Vec3& a, const Vec3& b, float s) { return a + (b - a) * s; }

const Triangle kUnitTriangle{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};

// The frame's axes as the paper writes them: kz the largest magnitude (ties
// to the lower axis), kx and ky the next two cyclically, swapped when the
// direction along kz is negative.
TEST(WatertightTriangle, FrameAxesFollowThePaperForEveryOrderingSignAndTie) {
  const float magnitudes[] = {0.0f, 1.0f, 2.0f};
  for (float x : magnitudes)
    for (float y : magnitudes)
      for (float z : magnitudes)
        for (int signs = 0; signs < 8; ++signs) {
          const Vec3 d{(signs & 1) ? -x : x, (signs & 2) ? -y : y, (signs & 4) ? -z : z};   // -0 included
          const float a[3] = {std::fabs(d.x), std::fabs(d.y), std::fabs(d.z)}, c[3] = {d.x, d.y, d.z};
          const int kz = a[0] >= a[1] && a[0] >= a[2] ? 0 : (a[1] >= a[2] ? 1 : 2);
          int kx = (kz + 1) % 3, ky = (kz + 2) % 3;
          if (c[kz] < 0.0f) std::swap(kx, ky);
          const WatertightRay frame(d);
          EXPECT_EQ(frame.kz, kz) << d.x << " " << d.y << " " << d.z;
          EXPECT_EQ(frame.kx, kx) << d.x << " " << d.y << " " << d.z;
          EXPECT_EQ(frame.ky, ky) << d.x << " " << d.y << " " << d.z;
        }
}

TEST(WatertightTriangle, HitsInteriorEdgesAndVerticesOfOneTriangle) {
  // Axis-aligned rays, and oblique rays whose direction ratios are powers of
  // two: the shear is then exact and the ray passes exactly through the point.
  const Vec3 points[] = {{0.25f, 0.25f, 0}, {0.5f, 0, 0},  {0, 0.5f, 0}, {0.5f, 0.5f, 0},
                         {0.25f, 0.75f, 0}, {0, 0, 0},     {1, 0, 0},    {0, 1, 0}};
  const Vec3 directions[] = {{0, 0, -1}, {0, 0, 1}, {1, -2, 4}, {0.5f, 0.25f, -1}, {-4, 1, 2}};
  for (const Vec3& point : points) {
    for (const Vec3& direction : directions) {
      const Ray ray{point - direction * 3.0f, direction};
      float t, u, v;
      ASSERT_TRUE(hits(ray, kUnitTriangle, t, u, v))
          << "point " << point.x << "," << point.y << " direction " << direction.x << ","
          << direction.y << "," << direction.z;
      EXPECT_EQ(t, 3.0f);
      EXPECT_EQ(u, point.x);
      EXPECT_EQ(v, point.y);
    }
  }
}

TEST(WatertightTriangle, MissesJustOutsideTheEdges) {
  const Vec3 outside[] = {{-0.001f, 0.5f, 0}, {0.5f, -0.001f, 0}, {0.5f, 0.501f, 0},
                          {1.001f, 0, 0},     {-0.001f, -0.001f, 0}};
  for (const Vec3& point : outside)
    EXPECT_FALSE(hits(Ray{point + Vec3(0, 0, 1), {0, 0, -1}}, kUnitTriangle));
}

TEST(WatertightTriangle, BarycentricsOfAKnownHit) {
  const Triangle triangle{{1, 1, 1}, {3, 1, 1}, {1, 5, 1}};
  // The point (1.5, 3, 1) = 0.25 of the way to v1 and 0.5 of the way to v2.
  const Ray ray{{1.5f, 3, 5}, {0, 0, -2}};
  float t, u, v;
  ASSERT_TRUE(hits(ray, triangle, t, u, v));
  EXPECT_EQ(t, 2.0f);  // t is in units of the (unnormalised) direction
  EXPECT_FLOAT_EQ(u, 0.25f);
  EXPECT_FLOAT_EQ(v, 0.5f);

  // Oblique ray into a tilted triangle: the barycentrics rebuild the hit point.
  const Triangle tilted{{0.3f, -0.2f, 0.1f}, {2.1f, 0.4f, 0.7f}, {0.5f, 1.9f, -0.6f}};
  const Vec3 target = tilted.v0 * 0.2f + tilted.v1 * 0.5f + tilted.v2 * 0.3f;
  const Ray oblique{{-1, -2, 3}, target - Vec3(-1, -2, 3)};
  ASSERT_TRUE(hits(oblique, tilted, t, u, v));
  EXPECT_NEAR(t, 1.0f, 1e-5f);
  EXPECT_NEAR(u, 0.5f, 1e-5f);
  EXPECT_NEAR(v, 0.3f, 1e-5f);
  const Vec3 fromBarycentrics = tilted.v0 * (1 - u - v) + tilted.v1 * u + tilted.v2 * v;
  const Vec3 fromT = oblique.origin + oblique.direction * t;
  EXPECT_LT(length(fromBarycentrics - fromT), 1e-5f);
}

TEST(WatertightTriangle, IsTwoSided) {
  float tFront, tBack, u, v;
  ASSERT_TRUE(hits(Ray{{0.2f, 0.2f, 1}, {0, 0, -1}}, kUnitTriangle, tFront, u, v));
  ASSERT_TRUE(hits(Ray{{0.2f, 0.2f, -1}, {0, 0, 1}}, kUnitTriangle, tBack, u, v));
  EXPECT_EQ(tFront, tBack);
  // Reversing the winding changes nothing either.
  const Triangle reversed{kUnitTriangle.v0, kUnitTriangle.v2, kUnitTriangle.v1};
  EXPECT_TRUE(hits(Ray{{0.2f, 0.2f, 1}, {0, 0, -1}}, reversed));
  EXPECT_TRUE(hits(Ray{{0.2f, 0.2f, -1}, {0, 0, 1}}, reversed));
}

TEST(WatertightTriangle, RaysInThePlaneMiss) {
  // Parallel to the plane, in it: det == 0, even through the interior.
  EXPECT_FALSE(hits(Ray{{-1, 0.25f, 0}, {1, 0, 0}}, kUnitTriangle));
  EXPECT_FALSE(hits(Ray{{-1, -1, 0}, {1, 1, 0}}, kUnitTriangle));
  EXPECT_FALSE(hits(Ray{{0.2f, 0.2f, 0}, {1, 0.5f, 0}}, kUnitTriangle));
  // Parallel to the plane, above it.
  EXPECT_FALSE(hits(Ray{{-1, 0.25f, 0.5f}, {1, 0, 0}}, kUnitTriangle));
}

TEST(WatertightTriangle, CountsOnlyTheOpenIntervalTminTmax) {
  const Vec3 origin{0.2f, 0.2f, 2};
  const Vec3 down{0, 0, -1};
  EXPECT_TRUE(hits(Ray{origin, down, 0, kInfinity}, kUnitTriangle));
  EXPECT_FALSE(hits(Ray{origin, -down, 0, kInfinity}, kUnitTriangle));  // behind the origin
  EXPECT_TRUE(hits(Ray{origin, -down, -kInfinity, kInfinity}, kUnitTriangle));
  EXPECT_FALSE(hits(Ray{origin, down, 2.5f, kInfinity}, kUnitTriangle));  // before tMin
  EXPECT_FALSE(hits(Ray{origin, down, 0, 1.5f}, kUnitTriangle));          // beyond tMax
  // The hit is at exactly t = 2: both bounds are exclusive.
  EXPECT_FALSE(hits(Ray{origin, down, 2.0f, kInfinity}, kUnitTriangle));
  EXPECT_FALSE(hits(Ray{origin, down, 0, 2.0f}, kUnitTriangle));
  EXPECT_TRUE(hits(Ray{origin, down, std::nextafter(2.0f, 0.0f), std::nextafter(2.0f, 3.0f)},
                   kUnitTriangle));
}

TEST(WatertightTriangle, DegenerateTrianglesNeverHit) {
  std::mt19937 random(11);
  std::uniform_real_distribution<float> coordinate(-1, 1);
  const auto point = [&] { return Vec3(coordinate(random), coordinate(random), coordinate(random)); };
  int tested = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec3 a = point(), b = point();
    // Two or three equal vertices, in every position.
    const Triangle degenerate[] = {{a, a, b}, {a, b, a}, {b, a, a}, {a, a, a}};
    for (const Triangle& triangle : degenerate) {
      // Rays aimed at the vertices, at the segment between them, and at random.
      const Vec3 targets[] = {a, b, lerp(a, b, 0.5f), lerp(a, b, coordinate(random)), point()};
      for (const Vec3& target : targets) {
        const Vec3 origin = point() * 4.0f;
        ASSERT_FALSE(hits(Ray{origin, target - origin, -kInfinity, kInfinity}, triangle));
        ++tested;
      }
    }
  }
  // Collinear vertices on a coordinate axis, with rays through the segment.
  const Triangle collinear{{0, 0, 0}, {1, 0, 0}, {3, 0, 0}};
  for (int i = 0; i < 2000; ++i) {
    const Vec3 target{coordinate(random) * 2 + 1, 0, 0};
    const Vec3 origin = point() * 4.0f;
    ASSERT_FALSE(hits(Ray{origin, target - origin}, collinear));
  }
  EXPECT_EQ(tested, 2000 * 4 * 5);
}

// A heightfield of (n x n) quads, two triangles each, with small random
// heights: every ray from well above or below crosses it, and none lies
// along any facet, so a ray aimed at a shared edge or vertex must hit.
std::vector<Triangle> heightfield(int n, std::mt19937& random) {
  std::uniform_real_distribution<float> height(-0.3f, 0.3f);
  std::vector<Vec3> vertices;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) vertices.push_back({float(x), float(y), height(random)});
  std::vector<Triangle> triangles;
  const auto at = [&](int x, int y) { return vertices[y * (n + 1) + x]; };
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      // Alternate the diagonal so vertices are shared by 4, 6 or 8 triangles.
      if ((x + y) % 2 == 0) {
        triangles.push_back({at(x, y), at(x + 1, y), at(x + 1, y + 1)});
        triangles.push_back({at(x, y), at(x + 1, y + 1), at(x, y + 1)});
      } else {
        triangles.push_back({at(x, y), at(x + 1, y), at(x, y + 1)});
        triangles.push_back({at(x + 1, y), at(x + 1, y + 1), at(x, y + 1)});
      }
    }
  return triangles;
}

TEST(WatertightTriangle, NoRayFallsThroughSharedEdgesOrVerticesOfAHeightfield) {
  std::mt19937 random(7);
  const int n = 6;
  const std::vector<Triangle> triangles = heightfield(n, random);
  std::uniform_real_distribution<float> unit(0, 1), offset(-4, 4), altitude(5, 9);
  int rays = 0;
  for (int i = 0; i < 40000; ++i) {
    // A random interior edge point or interior vertex of a random triangle.
    const Triangle& triangle = triangles[random() % triangles.size()];
    const Vec3 corners[3] = {triangle.v0, triangle.v1, triangle.v2};
    const int edge = int(random() % 3);
    const Vec3 target = i % 4 == 0 ? corners[edge]
                                   : lerp(corners[edge], corners[(edge + 1) % 3], unit(random));
    if (target.x <= 0 || target.y <= 0 || target.x >= n || target.y >= n) continue;  // boundary
    const float side = i % 2 == 0 ? 1.0f : -1.0f;
    const Vec3 origin{target.x + offset(random), target.y + offset(random), side * altitude(random)};
    const Ray ray{origin, target - origin};
    ASSERT_GE(countHits(ray, triangles), 1)
        << "ray from " << origin.x << "," << origin.y << "," << origin.z << " to " << target.x
        << "," << target.y << "," << target.z << " fell through";
    ++rays;
  }
  EXPECT_GT(rays, 20000);
}

TEST(WatertightTriangle, NoRayFallsThroughATriangleFan) {
  // A non-planar fan of 24 triangles around a centre vertex, crossed by rays
  // aimed at its centre and at points on its spokes (the shared edges).
  std::mt19937 random(3);
  std::uniform_real_distribution<float> unit(0, 1), jitter(-0.2f, 0.2f);
  const int spokes = 24;
  const Vec3 centre{0.013f, -0.007f, 0.05f};
  std::vector<Vec3> ring;
  for (int i = 0; i < spokes; ++i) {
    const float angle = 2 * kPi * (i + 0.3f * jitter(random)) / spokes;
    const float radius = 1 + jitter(random);
    // Heights small enough that no facet is seen edge-on from the rays below
    // (a ray grazing a silhouette edge may rightly miss).
    ring.push_back({radius * std::cos(angle), radius * std::sin(angle), 0.25f * jitter(random)});
  }
  std::vector<Triangle> fan;
  for (int i = 0; i < spokes; ++i) fan.push_back({centre, ring[i], ring[(i + 1) % spokes]});
  for (int i = 0; i < 40000; ++i) {
    const Vec3 target = i % 5 == 0 ? centre : lerp(centre, ring[random() % spokes], unit(random) * 0.99f);
    const Vec3 origin{jitter(random) * 10, jitter(random) * 10, (i % 2 ? 3.0f : -3.0f) + jitter(random)};
    const Ray ray{origin, target - origin};
    ASSERT_GE(countHits(ray, fan), 1) << "ray " << i << " fell through the fan";
  }
}

TEST(WatertightTriangle, NoRayEscapesAClosedMeshFromInside) {
  // A lumpy sphere (subdivided octahedron, radii 0.8..1.2), star-shaped
  // around the centre: every ray from near the centre crosses it.
  std::mt19937 random(5);
  std::uniform_real_distribution<float> unit(0, 1), radius(0.8f, 1.2f), small(-0.05f, 0.05f);
  const int n = 8;  // subdivisions per octant edge
  std::vector<Triangle> sphere;
  std::vector<Vec3> cache;  // one perturbed vertex per lattice point, shared by its triangles
  std::vector<Vec3> keys;
  const auto vertex = [&](Vec3 p) {
    p = normalize(p);
    for (size_t i = 0; i < keys.size(); ++i)
      if (length(keys[i] - p) < 1e-5f) return cache[i];
    keys.push_back(p);
    cache.push_back(p * radius(random));
    return cache.back();
  };
  for (int octant = 0; octant < 8; ++octant) {
    const Vec3 sx{octant & 1 ? -1.0f : 1.0f, 0, 0}, sy{0, octant & 2 ? -1.0f : 1.0f, 0},
        sz{0, 0, octant & 4 ? -1.0f : 1.0f};
    const auto lattice = [&](int i, int j) {  // i + j <= n
      return vertex(sx * float(n - i - j) + sy * float(i) + sz * float(j));
    };
    for (int i = 0; i < n; ++i)
      for (int j = 0; i + j < n; ++j) {
        sphere.push_back({lattice(i, j), lattice(i + 1, j), lattice(i, j + 1)});
        if (i + j + 2 <= n) sphere.push_back({lattice(i + 1, j), lattice(i + 1, j + 1), lattice(i, j + 1)});
      }
  }
  ASSERT_EQ(sphere.size(), size_t(8 * n * n));
  for (int i = 0; i < 30000; ++i) {
    const Vec3 origin{small(random), small(random), small(random)};
    const Triangle& triangle = sphere[random() % sphere.size()];
    const Vec3 corners[3] = {triangle.v0, triangle.v1, triangle.v2};
    const int edge = int(random() % 3);
    const Vec3 target = i % 3 == 0 ? corners[edge] : lerp(corners[edge], corners[(edge + 1) % 3], unit(random));
    const Ray ray{origin, target - origin};
    ASSERT_GE(countHits(ray, sphere), 1) << "ray " << i << " escaped through a crack";
  }
}

TEST(WatertightTriangle, SharedEdgeAtTheTieIsHitByBothSides) {
  // Two triangles sharing the edge x + y = 1 in the plane z = 0; a vertical
  // ray through the edge hits both at the same t.
  const Triangle lower{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const Triangle upper{{1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  float t0, t1, u, v;
  const Ray ray{{0.5f, 0.5f, 1}, {0, 0, -1}};
  ASSERT_TRUE(hits(ray, lower, t0, u, v));
  ASSERT_TRUE(hits(ray, upper, t1, u, v));
  EXPECT_EQ(t0, t1);
}

}  // namespace
}  // namespace portico
