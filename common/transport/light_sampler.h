// Chooses which area light a shading point samples, among the lights of its
// cell and of cells a few portals away (a building has thousands of lights;
// walls hide nearly all of them from any point). Every candidate light
// that can contribute keeps a nonzero probability; lights facing away, or
// below the point's tangent plane, get none. Two ways (JobSettings::
// LightSampling):
//  * Tree (the default): one descent of a light tree built over the
//    candidates (light_tree.h), ~2 log2(n) nodes looked at per choice.
//  * Scan: every candidate weighed, power over squared distance (a point
//    luminaire: its intensity towards the point over the squared
//    distance), n lights looked at per choice.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "common/job/job_settings.h"
#include "common/scene/store/scene_store.h"
#include "common/scene/store/scene_types.h"
#include "common/transport/light_choice.h"
#include "common/transport/light_tree.h"

namespace portico {

class LightSampler {
 public:
  // Samples among `candidates` (light ids, ascending). `lights` must
  // outlive the sampler (its point luminaires are read from it).
  LightSampler(const std::vector<AreaLight>& lights, std::vector<uint32_t> candidates,
               LightSampling sampling = LightSampling::Tree);
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

 private:
  LightChoice scan(const Vec3& point, const Vec3& normal, float u) const;

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
    // A point luminaire (weighed by its intensity towards the point); null for area lights.
    const AreaLight* point = nullptr;
  };
  std::vector<uint32_t> candidates_;
  std::vector<Candidate> prepared_;   // Scan: one per candidate, in the same order
  std::optional<LightTree> tree_;     // Tree
};

}  // namespace portico
