// The yardstick of `portico bench pipeline`: what a user would write instead
// of portico. Every cell's triangles in one Embree scene (one BVH over the
// whole building), and N threads tracing the job's photon pass through it
// with rtcIntersect1: the same emission (lights' shares in proportion to
// power, as coordinator/job_planner.cpp plans them) and the same steps at
// each surface as the cell kernel (common/transport/photon_scattering.h:
// the same random numbers, deposits, Russian roulette and bounce cap), so
// it does the same work as portico's photon phase, without cells.
#pragma once

#include "common/transport/photon_shares.h"

#include <cstdint>
#include <vector>

#include "common/scene/store/scene_store.h"

namespace portico::cli {

struct InCorePhotonOptions {
  uint64_t photons = 200000;
  uint64_t seed = 1;
  uint32_t threads = 2;           // tracing threads, and Embree's build threads
  uint32_t maxBounces = 64;       // as JobSettings::maxPhotonBounces
  uint32_t photonsPerChunk = 4096;  // photons a thread takes at a time
};

struct InCorePhotonResult {
  uint32_t cells = 0;
  uint64_t triangles = 0;
  uint64_t bytesMapped = 0;       // cell files mapped
  int64_t bvhBytes = 0;           // what Embree allocated for the scene
  double loadSeconds = 0;         // mapping and validating the cell files
  double buildSeconds = 0;        // Embree's device (thread pool), geometries and BVH (commit)
  double deviceSeconds = 0;       // of which making the device
  double traceSeconds = 0;        // the photon pass
  int64_t emitted = 0, deposits = 0, absorbed = 0, escaped = 0;
  int64_t rays = 0;               // rtcIntersect1 calls: one per segment (emission or bounce)
  std::vector<int64_t> depositsPerThread;
};

// Throws std::runtime_error (Embree's message, or a cell file's problem).
InCorePhotonResult runInCorePhotonTracer(const SceneStore& scene, const InCorePhotonOptions& options);


}  // namespace portico::cli
