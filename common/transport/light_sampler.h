// Chooses which area light a shading point samples, among the lights of its
// cell and of cells a few portals away (a building has thousands of lights;
// walls hide nearly all of them from any point). Weights follow each
// light's power over its squared distance (zero for lights facing away), so
// near, bright, visible-side lights get most samples; every candidate light
// that can contribute keeps a nonzero probability. A point luminaire weighs
// its intensity towards the point over the squared distance.
#pragma once

#include <cstdint>
#include <vector>

#include "common/scene/store/scene_store.h"
#include "common/scene/store/scene_types.h"

namespace portico {

struct LightChoice {
  uint32_t light = 0;
  float probability = 0;   // 0: no light can contribute
};

class LightSampler {
 public:
  // Samples among `candidates` (light ids). `lights` must outlive the
  // sampler (its point luminaires are read from it).
  LightSampler(const std::vector<AreaLight>& lights, std::vector<uint32_t> candidates);
  static std::vector<uint32_t> allLights(const std::vector<AreaLight>& lights);
  // The lights of cells within `hops` portals of `cell` (breadth first over
  // the portal graph); hops < 0: every light.
  static std::vector<uint32_t> lightsNear(const SceneStore& scene, uint32_t cell, int hops);
  // Per cell of the scene: whether it is within `hops` portals of `cell`
  // (hops < 0: every cell).
  static std::vector<bool> cellsNear(const SceneStore& scene, uint32_t cell, int hops);
  size_t candidateCount() const { return candidates_.size(); }
  // u in [0,1). Uses a thread-local scratch array; safe from several threads.
  LightChoice choose(const Vec3& point, const Vec3& normal, float u) const;
  // The pdf (per solid angle, for one sample) with which choose() and a
  // uniform point on the chosen light give `direction` (unit) from `point`:
  // that of the nearest candidate area light the ray meets from its front,
  // 0 when it meets none. What a glossy path's multiple importance sampling
  // weighs the light it meets by.
  float pdfAlong(const Vec3& point, const Vec3& normal, const Vec3& direction) const;

 private:
  // What choose() reads of a candidate, computed once per sampler: a room
  // two portals from a tower's corridor has hundreds of candidate lights,
  // and recomputing each one's normal, corners and power at every shading
  // point was most of a render's time there.
  struct Candidate {
    Vec3 center, normal;
    Vec3 corners[4];
    int cornerCount = 4;
    float reach = 0;       // half the diagonal (parallelogram), farthest corner (triangle)
    float luminousPower = 0;
    float area = 0;
    // A point luminaire (weighed by its intensity towards the point); null for area lights.
    const AreaLight* point = nullptr;
  };
  // Its share of choose()'s draws from `point` (before normalising).
  static double weight(const Candidate& light, const Vec3& point, const Vec3& normal);
  std::vector<uint32_t> candidates_;
  std::vector<Candidate> prepared_;   // one per candidate, in the same order
};

}  // namespace portico
