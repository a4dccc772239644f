// The bounds of a job's parameters. `portico render|submit` refuses a value
// outside them before anything starts, and the coordinator refuses it again
// at submit (validateSpec), so that a hand-made message gets no further.
// Each is well beyond what a production job asks for (docs/security.md,
// "Job limits"), and within what a coordinator queues in seconds and a lease
// traces in about a second's batches.
#pragma once

#include <cstdint>

namespace portico::limits {

// Photons of a job (queued as at most ~50 000 emission batches: job_planner.h).
constexpr uint64_t kMaxPhotons = 10'000'000'000;
constexpr uint32_t kMaxSpp = 65536;
// Rays spawned per camera hit: each multiplies a camera sample's work.
constexpr uint32_t kMaxGather = 1024;
constexpr uint32_t kMaxLightSamples = 1024;
constexpr uint32_t kMaxPhotonK = 4096;
constexpr double kMaxPhotonRadius = 1000;   // metres
constexpr uint32_t kMaxImageSide = 65536;
constexpr uint64_t kMaxImagePixels = uint64_t(1) << 28;   // 16384 x 16384
// Camera samples of a job (pixels x spp): 4 M camera batches at most.
constexpr uint64_t kMaxCameraSamples = uint64_t(1) << 36;
constexpr int kMaxLightHops = 1 << 20;      // -1: every light; -2: the store's default
constexpr double kMinExposure = 1e-9, kMaxExposure = 1e9;
// Render passes (--max-passes), each of the job's spp.
constexpr uint32_t kMaxPasses = 4096;
// --target-error: a relative standard error above 0, at most 100 %.
constexpr double kMaxTargetError = 1.0;
// --time-limit, seconds of render phase: above 0, at most a year.
constexpr double kMaxTimeLimitSeconds = 365.0 * 24 * 3600;
// A job's priority (`submit --priority`, `portico priority`): higher runs
// first; 0 by default.
constexpr int32_t kMinPriority = -1000, kMaxPriority = 1000;
// Portals of one cell: kMaxPortalsPerCell in common/scene/store/portal_geometry.h.

}  // namespace portico::limits
