#include "common/transport/light_tree.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>

#include "common/photometry/luminous_intensity.h"
#include "common/transport/light_sampler.h"

namespace portico {
namespace {

AreaLight quad(uint32_t id, Vec3 corner, Vec3 edge1, Vec3 edge2, float radiance) {
  AreaLight light;
  light.id = id;
  light.corner = corner, light.edge1 = edge1, light.edge2 = edge2;
  light.radiance = Vec3(radiance);
  return light;
}

// A downlight: light down to 60 degrees from the nadir, none above.
std::shared_ptr<const LuminousIntensity> downlight() {
  CandelaGrid grid;
  grid.vertical = {0, 30, 60, 90, 180};
  grid.horizontal = {0};
  grid.candela = {400, 300, 0, 0, 0};
  EXPECT_EQ(grid.problem(), "");
  return std::make_shared<const LuminousIntensity>(grid, "downlight.ies");
}

AreaLight pointLuminaire(uint32_t id, Vec3 at, Vec3 nadir, std::shared_ptr<const LuminousIntensity> intensity) {
  AreaLight light;
  light.id = id;
  light.shape = LightShape::Point;
  light.corner = at;
  light.edge1 = normalize(nadir);
  Vec3 t, b;
  orthonormalBasis(light.edge1, t, b);
  light.edge2 = t;
  light.intensity = std::move(intensity);
  light.radiance = Vec3(0.01f);
  return light;
}

// Whether a light can send any light to the upper side of the surface at
// `point` facing `normal`, worked out from the light itself: what a zero
// probability must mean.
bool canContribute(const AreaLight& light, const Vec3& point, const Vec3& normal) {
  if (light.isPoint()) {
    const Vec3 toPoint = point - light.corner;
    return dot(normal, toPoint) < 0 && maxComponent(light.intensityToward(normalize(toPoint))) > 0;
  }
  if (!(dot(light.normal(), point - light.center()) > 0)) return false;
  Vec3 corners[4];
  const int count = light.corners(corners);
  for (int k = 0; k < count; ++k)
    if (dot(normal, corners[k] - point) > 0) return true;
  return false;
}

// A building-like scatter: ceiling lights facing down on three floors, wall
// washers facing sideways, a few facing up, triangles, and downlights.
std::vector<AreaLight> manyLights(int count, uint32_t seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> x(-20, 20), size(0.2f, 1.2f), radiance(1, 50);
  std::uniform_int_distribution<int> floor(0, 2), kind(0, 9);
  const auto lamp = downlight();
  std::vector<AreaLight> lights;
  for (int i = 0; i < count; ++i) {
    const uint32_t id = static_cast<uint32_t>(i);
    const float y = 3.0f * floor(random) + 2.8f, s = size(random);
    const Vec3 at(x(random), y, x(random));
    switch (kind(random)) {
      case 0:   // facing +X on a wall
        lights.push_back(quad(id, at, {0, s, 0}, {0, 0, s}, radiance(random)));
        break;
      case 1:   // facing up
        lights.push_back(quad(id, at, {0, 0, s}, {s, 0, 0}, radiance(random)));
        break;
      case 2:
        lights.push_back(pointLuminaire(id, at, {0, -1, 0}, lamp));
        break;
      case 3: {   // a triangle facing down
        AreaLight t = quad(id, at, {s, 0, 0}, {0, 0, s}, radiance(random));
        t.shape = LightShape::Triangle;
        lights.push_back(t);
        break;
      }
      default:   // facing down on a ceiling
        lights.push_back(quad(id, at, {s, 0, 0}, {0, 0, s}, radiance(random)));
    }
  }
  return lights;
}

Vec3 randomDirection(std::mt19937& random) {
  std::normal_distribution<float> gauss;
  return normalize(Vec3(gauss(random), gauss(random), gauss(random)));
}

TEST(LightTree, ProbabilitiesSumToOneWhenEveryLightCanContribute) {
  // Ceiling lights above a floor: from any point of the floor, facing up,
  // each of them can contribute, so no descent can end at a dark node.
  std::vector<AreaLight> lights;
  std::mt19937 random(7);
  std::uniform_real_distribution<float> x(-20, 20), size(0.2f, 1.2f), radiance(1, 50);
  for (uint32_t i = 0; i < 300; ++i) {
    const float s = size(random);
    lights.push_back(quad(i, {x(random), 2.8f, x(random)}, {s, 0, 0}, {0, 0, s}, radiance(random)));
  }
  const LightTree tree(lights, LightSampler::allLights(lights));
  ASSERT_EQ(tree.lightCount(), lights.size());
  ASSERT_EQ(tree.nodeCount(), 2 * lights.size() - 1);
  for (int p = 0; p < 50; ++p) {
    const Vec3 point(x(random), 0, x(random));
    double sum = 0;
    for (const AreaLight& light : lights) {
      const double probability = tree.probability(point, {0, 1, 0}, light.id);
      EXPECT_GT(probability, 0) << "light " << light.id;
      sum += probability;
    }
    EXPECT_NEAR(sum, 1.0, 1e-5) << "point " << p;
  }
}

TEST(LightTree, ChoicesFollowTheProbabilitiesItReports) {
  const std::vector<AreaLight> lights = manyLights(200, 3);
  const LightTree tree(lights, LightSampler::allLights(lights));
  std::mt19937 random(11);
  std::uniform_real_distribution<float> x(-20, 20), y(0, 9);
  for (int p = 0; p < 12; ++p) {
    const Vec3 point(x(random), y(random), x(random));
    const Vec3 normal = randomDirection(random);
    std::vector<double> probability(lights.size());
    double sum = 0;
    for (const AreaLight& light : lights) sum += probability[light.id] = tree.probability(point, normal, light.id);
    ASSERT_LE(sum, 1.0 + 1e-5);
    // Stratified numbers: every light's share of them is its probability,
    // up to the stratification's 1 / n per boundary crossed.
    constexpr int kDraws = 200000;
    std::vector<int> counts(lights.size(), 0);
    int none = 0;
    for (int i = 0; i < kDraws; ++i) {
      const LightChoice choice = tree.choose(point, normal, (i + 0.5f) / kDraws);
      if (choice.probability <= 0) {
        ++none;
        continue;
      }
      ++counts[choice.light];
      // The probability a choice carries is the one reported for its light.
      ASSERT_NEAR(choice.probability, probability[choice.light], 1e-6 + 1e-4 * probability[choice.light]);
    }
    for (const AreaLight& light : lights)
      EXPECT_NEAR(counts[light.id] / double(kDraws), probability[light.id], 2e-4) << "point " << p << " light " << light.id;
    // Descents that end on a node with nothing lit under it choose nothing:
    // exactly the probability missing from the sum.
    EXPECT_NEAR(none / double(kDraws), 1.0 - sum, 2e-4) << "point " << p;
  }
}

TEST(LightTree, ALightHasNoProbabilityExactlyWhereItCannotContribute) {
  const std::vector<AreaLight> lights = manyLights(400, 5);
  const LightTree tree(lights, LightSampler::allLights(lights));
  std::mt19937 random(13);
  std::uniform_real_distribution<float> x(-20, 20), y(0, 9);
  int dark = 0, lit = 0;
  for (int p = 0; p < 200; ++p) {
    const Vec3 point(x(random), y(random), x(random));
    const Vec3 normal = randomDirection(random);
    for (const AreaLight& light : lights) {
      const bool contributes = canContribute(light, point, normal);
      EXPECT_EQ(tree.probability(point, normal, light.id) > 0, contributes)
          << "point " << p << " light " << light.id << (light.isPoint() ? " (luminaire)" : "");
      (contributes ? lit : dark)++;
    }
  }
  // Both cases were met many times.
  EXPECT_GT(dark, 10000);
  EXPECT_GT(lit, 10000);
}

TEST(LightTree, ADownlightIsDarkAboveItsWidestAngleOnly) {
  std::vector<AreaLight> lights{pointLuminaire(0, {0, 3, 0}, {0, -1, 0}, downlight()),
                                quad(1, {5, 3, 5}, {1, 0, 0}, {0, 0, 1}, 10)};
  const LightTree tree(lights, LightSampler::allLights(lights));
  const LightBounds bounds = LightTree::boundsOf(lights[0]);
  EXPECT_GT(bounds.cosSpread, 0.0f);   // a cone narrower than the lower hemisphere
  // Straight below: lit. 80 degrees from the nadir (a wall beside it): its
  // file gives nothing there, so the luminaire is never chosen.
  EXPECT_GT(tree.probability({0, 0, 0}, {0, 1, 0}, 0), 0.0);
  const float at80 = std::tan(80 * kPi / 180) * 1.0f;
  EXPECT_EQ(tree.probability({at80, 2, 0}, {-1, 0, 0}, 0), 0.0);
  EXPECT_NEAR(tree.probability({at80, 2, 0}, {-1, 0, 0}, 1), 1.0, 1e-6);
}

TEST(LightTree, TheSameLightsInAnyOrderGiveTheSameChoicesBitForBit) {
  const std::vector<AreaLight> lights = manyLights(300, 9);
  std::vector<uint32_t> shuffled = LightSampler::allLights(lights);
  std::shuffle(shuffled.begin(), shuffled.end(), std::mt19937(17));
  const LightTree a(lights, LightSampler::allLights(lights)), b(lights, shuffled);
  std::mt19937 random(19);
  std::uniform_real_distribution<float> x(-20, 20), y(0, 9), u(0, 1);
  for (int i = 0; i < 2000; ++i) {
    const Vec3 point(x(random), y(random), x(random)), normal = randomDirection(random);
    const float number = u(random);
    const LightChoice first = a.choose(point, normal, number), second = b.choose(point, normal, number);
    EXPECT_EQ(first.light, second.light);
    EXPECT_EQ(first.probability, second.probability);
  }
}

// The descent looks at two nodes per level: ~2 log2(n), not n.
TEST(LightTree, IsShallowOverABuildingsLights) {
  const std::vector<AreaLight> lights = manyLights(4096, 21);
  const LightTree tree(lights, LightSampler::allLights(lights));
  EXPECT_EQ(tree.nodeCount(), 2 * tree.lightCount() - 1);
  EXPECT_GE(tree.depth(), 12u);   // log2(4096)
  EXPECT_LE(tree.depth(), 36u);   // within 3 log2(n)
  const LightChoice choice = tree.choose({19, 0.5f, 19}, {0, 1, 0}, 0.5f);
  EXPECT_GT(choice.probability, 0.0f);
}

}  // namespace
}  // namespace portico
