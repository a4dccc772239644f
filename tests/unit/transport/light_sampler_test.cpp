#include "common/transport/light_sampler.h"

#include <gtest/gtest.h>

namespace portico {
namespace {

AreaLight ceilingLight(uint32_t id, Vec3 center, float size, float radiance) {
  AreaLight light;
  light.id = id;
  // Facing down: cross(edge1, edge2) = -Y.
  light.corner = center - Vec3(size / 2, 0, size / 2);
  light.edge1 = {size, 0, 0};
  light.edge2 = {0, 0, size};
  light.radiance = Vec3(radiance);
  return light;
}

TEST(LightSampler, ProbabilitiesMatchSelectionFrequencies) {
  std::vector<AreaLight> lights{ceilingLight(0, {0, 3, 0}, 1, 10), ceilingLight(1, {4, 3, 0}, 1, 10),
                                ceilingLight(2, {0, 3, 8}, 0.5f, 40)};
  ASSERT_LT(lights[0].normal().y, 0);
  for (LightSampling sampling : {LightSampling::Scan, LightSampling::Tree}) {
    SCOPED_TRACE(toString(sampling));
    LightSampler sampler(lights, LightSampler::allLights(lights), sampling);
    const Vec3 point(1, 0, 1), normal(0, 1, 0);
    std::vector<int> counts(3, 0);
    std::vector<float> probability(3, 0);
    const int n = 100000;
    for (int i = 0; i < n; ++i) {
      const LightChoice c = sampler.choose(point, normal, (i + 0.5f) / n);
      ASSERT_GT(c.probability, 0);
      counts[c.light]++;
      probability[c.light] = c.probability;
    }
    float total = 0;
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(counts[i] / double(n), probability[i], 1e-3) << i;
      total += probability[i];
    }
    EXPECT_NEAR(total, 1.0f, 1e-5f);
    EXPECT_GT(probability[0], probability[1]);   // nearer light gets more samples
  }
}

TEST(LightSampler, LightsThatCannotContributeAreNeverChosen) {
  // Light 1 is below the shading point's floor plane and faces down, away.
  std::vector<AreaLight> lights{ceilingLight(0, {0, 3, 0}, 1, 10), ceilingLight(1, {0, -2, 0}, 1, 10)};
  for (LightSampling sampling : {LightSampling::Scan, LightSampling::Tree}) {
    SCOPED_TRACE(toString(sampling));
    LightSampler sampler(lights, LightSampler::allLights(lights), sampling);
    for (int i = 0; i < 1000; ++i) {
      const LightChoice c = sampler.choose({0, 0, 0}, {0, 1, 0}, i / 1000.0f);
      EXPECT_EQ(c.light, 0u);
      EXPECT_FLOAT_EQ(c.probability, 1.0f);
    }
    // A point above every light sees only their dark backs.
    EXPECT_EQ(sampler.choose({0, 10, 0}, {0, 1, 0}, 0.3f).probability, 0.0f);
  }
}

}  // namespace
}  // namespace portico

#include <filesystem>
#include <unistd.h>

#include "common/scene/generator/demo_generator.h"
#include "common/scene/import/building_importer.h"

namespace portico {
namespace {

TEST(LightSampler, LightsNearFollowThePortalGraph) {
  // two_rooms: roomA (the light) - door - roomB. From roomB the light is two
  // portals away: hops 2 reaches it, hops 1 does not.
  const auto store = std::filesystem::temp_directory_path() / ("portico-lights-near-" + std::to_string(getpid()));
  std::filesystem::remove_all(store);
  importBuilding({std::string(PORTICO_REFERENCE_DIR) + "/two_rooms/scene.json"}, store.string());
  const SceneStore scene = SceneStore::open(store.string());
  const uint32_t roomB = scene.camera().cell;
  const uint32_t roomA = scene.lights()[0].cell;
  EXPECT_EQ(LightSampler::lightsNear(scene, roomA, 0).size(), 1u);
  EXPECT_TRUE(LightSampler::lightsNear(scene, roomB, 0).empty());
  EXPECT_TRUE(LightSampler::lightsNear(scene, roomB, 1).empty());
  EXPECT_EQ(LightSampler::lightsNear(scene, roomB, 2).size(), 1u);
  EXPECT_EQ(LightSampler::lightsNear(scene, roomB, -1).size(), 1u);
  std::filesystem::remove_all(store);
}

// On the demo (a corridor, six rooms, five lights), for every cell and
// hops 0-3: the lights of the cells within that many portals, in light
// order, as a breadth-first search over the whole portal list finds them.
TEST(LightSampler, LightsNearAreTheLightsOfTheCellsWithinHopsInLightOrder) {
  const auto store = std::filesystem::temp_directory_path() / ("portico-lights-demo-" + std::to_string(getpid()));
  std::filesystem::remove_all(store);
  generateDemoBuilding(store.string(), 3);
  const SceneStore scene = SceneStore::open(store.string());
  for (uint32_t cell = 0; cell < scene.cells().size(); ++cell)
    for (int hops = 0; hops <= 3; ++hops) {
      std::vector<int> distance(scene.cells().size(), -1);
      distance[cell] = 0;
      for (int step = 0; step < hops; ++step)
        for (const Portal& p : scene.portals())
          for (auto [from, to] : {std::pair{p.cellA, p.cellB}, std::pair{p.cellB, p.cellA}})
            if (distance[from] == step && distance[to] < 0) distance[to] = step + 1;
      std::vector<uint32_t> expected;
      for (const AreaLight& light : scene.lights())
        if (distance[light.cell] >= 0) expected.push_back(light.id);
      EXPECT_EQ(LightSampler::lightsNear(scene, cell, hops), expected) << "cell " << cell << ", hops " << hops;
    }
  std::filesystem::remove_all(store);
}

// A triangle light's points cover it uniformly: all inside, their mean at
// the centroid, each half of the triangle (split by a median) half of them.
TEST(AreaLightShape, TrianglePointsAreUniform) {
  AreaLight triangle;
  triangle.shape = LightShape::Triangle;
  triangle.corner = {1, 2, 3};
  triangle.edge1 = {2, 0, 0};
  triangle.edge2 = {0, 0, 1};
  EXPECT_FLOAT_EQ(triangle.area(), 1.0f);
  Vec3 mean(0.0f);
  int nearHalf = 0;
  const int n = 200;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const Vec3 p = triangle.pointAt((i + 0.5f) / n, (j + 0.5f) / n);
      const float s = (p.x - 1.0f) / 2.0f, t = p.z - 3.0f;
      ASSERT_TRUE(s >= 0 && t >= 0 && s + t <= 1.0f + 1e-6f && p.y == 2.0f) << i << " " << j;
      mean += p;
      nearHalf += s < t ? 1 : 0;   // one side of the median through corner 0
    }
  mean *= 1.0f / float(n * n);
  EXPECT_NEAR(length(mean - triangle.center()), 0.0f, 2e-3f);
  EXPECT_NEAR(nearHalf / double(n * n), 0.5, 0.01);
}

// A parallelogram keeps corner + u edge1 + v edge2, bit for bit.
TEST(AreaLightShape, ParallelogramPointsAreTheBilinearMap) {
  const AreaLight quad = ceilingLight(0, {0.3f, 3, 0.7f}, 1.3f, 1);
  for (float u : {0.0f, 0.123f, 0.5f, 0.999f})
    for (float v : {0.0f, 0.77f, 0.999f}) {
      const Vec3 expected = quad.corner + quad.edge1 * u + quad.edge2 * v;
      EXPECT_EQ(quad.pointAt(u, v), expected);
    }
}

// A triangle light beside a quad light of twice its area and the same
// radiance: half the quad's power, so half its weight from a point equally
// far (the scan's weights: power over squared distance).
TEST(LightSampler, TriangleLightsWeighByTheirPower) {
  std::vector<AreaLight> lights{ceilingLight(0, {-2, 3, 0}, 1, 10), ceilingLight(1, {2, 3, 0}, 1, 10)};
  lights[1].shape = LightShape::Triangle;
  lights[1].corner = Vec3(2, 3, 0) - (lights[1].edge1 + lights[1].edge2) * (1.0f / 3.0f);   // centroid at (2, 3, 0)
  ASSERT_NEAR(length(lights[1].center() - Vec3(2, 3, 0)), 0.0f, 1e-6f);
  LightSampler sampler(lights, LightSampler::allLights(lights), LightSampling::Scan);
  const LightChoice quad = sampler.choose({0, 0, 0}, {0, 1, 0}, 0.1f);
  const LightChoice triangle = sampler.choose({0, 0, 0}, {0, 1, 0}, 0.9f);
  ASSERT_EQ(quad.light, 0u);
  ASSERT_EQ(triangle.light, 1u);
  EXPECT_NEAR(quad.probability, 2.0f / 3.0f, 1e-5f);
  EXPECT_NEAR(triangle.probability, 1.0f / 3.0f, 1e-5f);
}

}  // namespace
}  // namespace portico
