#include "common/accel/embree_accelerator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "common/accel/accelerator.h"
#include "common/accel/brute_force.h"
#include "tests/unit/accel/accel_test_scenes.h"

namespace portico {
namespace {

using accel_test::TestMesh;

// Embree has its own triangle test, so it is compared with brute force only
// where the answer does not hang on rounding: every triangle is clearly
// missed or clearly hit (barycentrics, in double, away from the edges; the
// ray not in its plane), t clearly inside (tMin, tMax), and no second hit
// within a relative 1e-3 of the nearest.
bool unambiguous(const TestMesh& mesh, const Ray& ray) {
  constexpr double kEdgeMargin = 1e-4, kDepthMargin = 1e-3;
  const double o[3] = {ray.origin.x, ray.origin.y, ray.origin.z};
  const double d[3] = {ray.direction.x, ray.direction.y, ray.direction.z};
  const double directionLength = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  double nearest = std::numeric_limits<double>::infinity(), second = nearest;
  for (size_t t = 0; t < mesh.triangleCount(); ++t) {
    const Vec3 a = mesh.vertex(mesh.indices[3 * t]), b = mesh.vertex(mesh.indices[3 * t + 1]),
               c = mesh.vertex(mesh.indices[3 * t + 2]);
    const double e1[3] = {double(b.x) - a.x, double(b.y) - a.y, double(b.z) - a.z};
    const double e2[3] = {double(c.x) - a.x, double(c.y) - a.y, double(c.z) - a.z};
    const double p[3] = {d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2], d[0] * e2[1] - d[1] * e2[0]};
    const double det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
    const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                         e1[0] * e2[1] - e1[1] * e2[0]};
    const double area2 = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (area2 == 0) continue;  // degenerate: never hit by either
    // |det| = |n . d|: a ray (nearly) in the triangle's plane is ambiguous
    // if it could touch it at all; treat it as such.
    const double s[3] = {o[0] - a.x, o[1] - a.y, o[2] - a.z};
    if (std::fabs(det) < 1e-6 * area2 * directionLength) {
      const double distance = std::fabs(s[0] * n[0] + s[1] * n[1] + s[2] * n[2]) / area2;
      if (distance < 1e-3) return false;
      continue;
    }
    const double inverse = 1.0 / det;
    const double u = (s[0] * p[0] + s[1] * p[1] + s[2] * p[2]) * inverse;
    const double q[3] = {s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2], s[0] * e1[1] - s[1] * e1[0]};
    const double v = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) * inverse;
    const double hitT = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) * inverse;
    const double w = 1.0 - u - v;
    // Both tests round the vertices' positions relative to the ray origin
    // (and the ray itself) to float: a hit point is only known to about
    // 1e-6 of its distance from the origin and from the world origin, which
    // is a larger fraction of a small triangle's size.
    const double inside = std::min({u, v, w});
    const double hitDistance = std::fabs(hitT) * directionLength;
    const double originDistance = std::sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]);
    const double e3[3] = {e2[0] - e1[0], e2[1] - e1[1], e2[2] - e1[2]};
    const double longestEdge = std::sqrt(std::max({e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2],
                                                   e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2],
                                                   e3[0] * e3[0] + e3[1] * e3[1] + e3[2] * e3[2]}));
    const double smallestAltitude = area2 / longestEdge;
    const double edgeMargin =
        std::max(kEdgeMargin, 1e-5 * (hitDistance + originDistance + 1.0) / smallestAltitude);
    if (std::fabs(inside) < edgeMargin) return false;  // grazes an edge or a vertex
    if (inside < 0) continue;
    const double scale = std::max(1e-3, std::fabs(hitT));
    if (std::fabs(hitT - ray.tMin) < kDepthMargin * scale || std::fabs(hitT - ray.tMax) < kDepthMargin * scale)
      return false;
    if (!(hitT > ray.tMin && hitT < ray.tMax)) continue;
    // t is only known to about 1e-6 of the coordinates' size over the cosine
    // of incidence: a grazing hit, or one right at the origin, is not clear-cut.
    const double cosine = std::fabs(det) / (area2 * directionLength);
    if (cosine < 0.1 || hitDistance < 0.05 * (originDistance + 1.0)) return false;
    if (hitT < nearest) {
      second = nearest;
      nearest = hitT;
    } else if (hitT < second) {
      second = hitT;
    }
  }
  return !(second - nearest < kDepthMargin * std::max(1e-3, nearest));
}

struct Agreement {
  int compared = 0, hits = 0;
};

Agreement expectAgreesWithBruteForce(const TestMesh& mesh, const Accelerator& embree, int rayCount, uint32_t seed) {
  const BruteForce brute(mesh.view());
  Agreement agreement;
  int mismatches = 0;
  for (const Ray& ray : accel_test::testRays(mesh, rayCount, seed)) {
    if (!unambiguous(mesh, ray)) continue;
    ++agreement.compared;
    const Hit expected = brute.intersect(ray);
    const Hit got = embree.intersect(ray);
    agreement.hits += expected.found();
    bool same = got.primitive == expected.primitive && embree.occluded(ray) == expected.found();
    if (same && expected.found()) {
      same = std::fabs(got.t - expected.t) <= 1e-4f * expected.t && std::fabs(got.u - expected.u) <= 1e-3f &&
             std::fabs(got.v - expected.v) <= 1e-3f;
    }
    if (!same && ++mismatches <= 5)
      ADD_FAILURE() << accel_test::describe(ray) << ": brute force primitive " << expected.primitive << " t "
                    << expected.t << ", embree primitive " << got.primitive << " t " << got.t << " occluded "
                    << embree.occluded(ray);
  }
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(agreement.compared, rayCount / 2);  // most rays are clear-cut
  return agreement;
}

// A mesh whose positions vector holds one float after the last vertex, and
// says so: Embree may then share it.
MeshView paddedView(TestMesh& mesh) {
  const size_t vertices = mesh.positions.size() / 3;
  mesh.positions.push_back(0.0f);
  MeshView view = mesh.view();
  view.vertexCount = vertices;
  view.positionsPaddingFloats = 1;
  return view;
}

TEST(EmbreeAccelerator, AgreesWithBruteForceOnClearCutRays) {
  const FlushDenormalsScope flushDenormals;
  std::mt19937 random(1);
  TestMesh soup, room, thin, cluster;
  accel_test::addRandomTriangles(soup, 1500, random);
  accel_test::addRoomOfBoxes(room, random);
  accel_test::addLongThinTriangles(thin, 200, random);
  accel_test::addClusterInEmptyRoom(cluster, 2000, random);
  const TestMesh hall = accel_test::furnishedHall(5000, 3);
  const TestMesh mixed = accel_test::mixedScene(2);
  for (const TestMesh* mesh : std::initializer_list<const TestMesh*>{&soup, &room, &thin, &cluster, &hall, &mixed}) {
    SCOPED_TRACE(std::to_string(mesh->triangleCount()) + " triangles");
    for (const EmbreeBuildQuality quality :
         {EmbreeBuildQuality::Low, EmbreeBuildQuality::Medium, EmbreeBuildQuality::High}) {
      SCOPED_TRACE("build quality " + std::to_string(int(quality)));
      const EmbreeAccelerator embree(mesh->view(), "embree", quality);
      const Agreement agreement = expectAgreesWithBruteForce(*mesh, embree, 3000, 10);
      // Not only misses (long thin triangles are mostly hit at grazing angles
      // or near an edge, so few of their hits are clear-cut).
      EXPECT_GT(agreement.hits, 10);
    }
  }
}

TEST(EmbreeAccelerator, SharesPaddedVerticesAndCopiesOthers) {
  const FlushDenormalsScope flushDenormals;
  TestMesh padded = accel_test::furnishedHall(3000, 4);
  const TestMesh plain = padded;
  const EmbreeAccelerator shared(paddedView(padded));
  const EmbreeAccelerator copied(plain.view());
  EXPECT_TRUE(shared.sharesVertices());
  EXPECT_FALSE(copied.sharesVertices());
  EXPECT_GT(copied.stats().bytes, shared.stats().bytes);
  // The same scene either way: the same answers.
  for (const Ray& ray : accel_test::testRays(plain, 4000, 20)) {
    const Hit a = shared.intersect(ray), b = copied.intersect(ray);
    ASSERT_EQ(std::memcmp(&a, &b, sizeof(Hit)), 0) << accel_test::describe(ray);
    ASSERT_EQ(shared.occluded(ray), copied.occluded(ray));
  }
  expectAgreesWithBruteForce(plain, shared, 3000, 21);
}

TEST(EmbreeAccelerator, RespectsTheOpenRayInterval) {
  const FlushDenormalsScope flushDenormals;
  TestMesh mesh;
  mesh.addTriangle({-1, -1, 1}, {3, -1, 1}, {-1, 3, 1});
  mesh.addTriangle({-1, -1, 2}, {3, -1, 2}, {-1, 3, 2});
  const EmbreeAccelerator embree(mesh.view());
  const Ray up{{0, 0, 0}, {0, 0, 1}};
  EXPECT_EQ(embree.intersect(up).primitive, 0u);
  // Embree's own triangle test divides by a reciprocal estimate: t within
  // a few ulps (exact on AVX-512 machines, one ulp off on some AVX2 ones).
  EXPECT_FLOAT_EQ(embree.intersect(up).t, 1.0f);
  // tMin < t < tMax, both bounds exclusive, as for every accelerator.
  EXPECT_FALSE(embree.occluded(Ray{{0, 0, 0}, {0, 0, 1}, 0.0f, 1.0f}));
  EXPECT_FALSE(embree.intersect(Ray{{0, 0, 0}, {0, 0, 1}, 0.0f, 1.0f}).found());
  EXPECT_EQ(embree.intersect(Ray{{0, 0, 0}, {0, 0, 1}, 0.0f, std::nextafter(1.0f, 2.0f)}).primitive, 0u);
  EXPECT_EQ(embree.intersect(Ray{{0, 0, 0}, {0, 0, 1}, 1.0f, kInfinity}).primitive, 1u);
  EXPECT_TRUE(embree.occluded(Ray{{0, 0, 0}, {0, 0, 2}, 0.0f, 0.75f}));  // t = 0.5 with |d| = 2
  EXPECT_FLOAT_EQ(embree.intersect(Ray{{0, 0, 0}, {0, 0, 2}}).t, 0.5f);
  // Barycentrics follow portico's convention (weights of vertices 1 and 2).
  const Hit hit = embree.intersect(Ray{{1, 0, 0}, {0, 0, 1}});
  EXPECT_NEAR(hit.u, 0.5f, 1e-6f);
  EXPECT_NEAR(hit.v, 0.25f, 1e-6f);

  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (const Ray& ray : {Ray{{0, 0, 0}, {0, 0, 0}}, Ray{{nan, 0, 0}, {0, 0, 1}}, Ray{{0, 0, 0}, {0, nan, 1}},
                         Ray{{0, 0, 0}, {0, 0, 1}, 2.0f, 1.0f}}) {
    EXPECT_FALSE(embree.intersect(ray).found());
    EXPECT_FALSE(embree.occluded(ray));
  }
}

TEST(EmbreeAccelerator, HandlesEmptyMeshesAndReportsStatistics) {
  const FlushDenormalsScope flushDenormals;
  const TestMesh empty;
  const EmbreeAccelerator nothing(empty.view());
  EXPECT_FALSE(nothing.intersect(Ray{{0, 0, 0}, {1, 0, 0}}).found());
  EXPECT_FALSE(nothing.occluded(Ray{{0, 0, 0}, {1, 0, 0}}));
  EXPECT_TRUE(nothing.bounds().empty());

  const TestMesh mesh = accel_test::mixedScene(5);
  const auto embree = buildAccelerator(parseAcceleratorSpec("embree"), mesh.view());
  const AcceleratorStats& stats = embree->stats();
  EXPECT_EQ(stats.spec, "embree");
  EXPECT_EQ(stats.triangleReferences, mesh.triangleCount());
  EXPECT_GT(stats.bytes, mesh.triangleCount() * 8);  // the BVH, as the device counted it
  EXPECT_GE(stats.buildMs, 0.0);
  const BruteForce brute(mesh.view());
  EXPECT_EQ(embree->bounds().lo, brute.bounds().lo);
  EXPECT_EQ(embree->bounds().hi, brute.bounds().hi);

  // One device per process, configured before its first use only.
  EXPECT_TRUE(configureEmbreeDevice(""));
  EXPECT_FALSE(configureEmbreeDevice("threads=1"));
}

TEST(EmbreeAccelerator, AnswersFromManyThreadsAtOnce) {
  const TestMesh mesh = accel_test::furnishedHall(20000, 6);
  const EmbreeAccelerator embree(mesh.view());
  const std::vector<Ray> rays = accel_test::testRays(mesh, 4000, 60);
  std::vector<Hit> expected;
  {
    const FlushDenormalsScope flushDenormals;
    for (const Ray& ray : rays) expected.push_back(embree.intersect(ray));
  }
  std::vector<int> mismatches(4, 0);
  std::vector<std::thread> threads;
  for (int thread = 0; thread < 4; ++thread)
    threads.emplace_back([&, thread] {
      const FlushDenormalsScope flushDenormals;
      for (int pass = 0; pass < 2; ++pass)
        for (size_t i = 0; i < rays.size(); ++i) {
          const Hit hit = embree.intersect(rays[i]);
          mismatches[thread] += std::memcmp(&hit, &expected[i], sizeof(Hit)) != 0 ||
                                embree.occluded(rays[i]) != expected[i].found();
        }
    });
  for (std::thread& thread : threads) thread.join();
  for (int count : mismatches) EXPECT_EQ(count, 0);
}

TEST(EmbreeAcceleratorSpec, TakesABuildQualityAndNoParameters) {
  const TestMesh mesh = accel_test::mixedScene(7);
  const auto errorOf = [&](const char* text) -> std::string {
    try {
      buildAccelerator(parseAcceleratorSpec(text), mesh.view());
    } catch (const std::invalid_argument& error) {
      return error.what();
    }
    return "(no error)";
  };
  EXPECT_EQ(errorOf("embree:quality=high"),
            "accelerator spec 'embree:quality=high': unknown parameter 'quality' for embree (it takes none)");
  EXPECT_EQ(errorOf("embree:fast"),
            "accelerator spec 'embree:fast': unknown variant 'fast' for embree (known: low, medium, high)");
  for (const char* text : {"embree", "embree:low", "embree:medium", "embree:high"})
    EXPECT_NO_THROW(validateAcceleratorSpec(parseAcceleratorSpec(text))) << text;
}

}  // namespace
}  // namespace portico
