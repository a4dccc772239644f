// Turns a submitted job into its first queued work, and a finished photon
// phase into camera work: compact generator batches (EmitRange,
// CameraRange) that workers expand themselves.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>

#include "common/job/job_settings.h"
#include "common/scene/store/scene_store.h"
#include "coordinator/job_store.h"
#include "proto/wire.capnp.h"

namespace portico {

// Photons handed to one emission batch, camera samples to one camera batch:
// each about a tenth to a half of a second of tracing on one core.
constexpr uint32_t kPhotonsPerEmitBatch = 20000;
constexpr uint64_t kMostEmitBatches = 50000;   // a billion photons; beyond, batches grow
constexpr uint32_t kSamplesPerCameraBatch = 16384;

// The photon count of a job that names none (docs/large-buildings.md,
// "Default photon count"): kDefaultPhotonsPerLight per light of the
// building, at least kMinDefaultPhotons (what the reference scenes'
// image-quality defaults are measured at), and at most kMaxDefaultPhotons
// (a default render of the largest buildings stays minutes of photon pass
// on one machine).
constexpr uint64_t kDefaultPhotonsPerLight = 5000;
constexpr uint64_t kMinDefaultPhotons = 400000;
constexpr uint64_t kMaxDefaultPhotons = 20000000;
uint64_t defaultPhotonCount(size_t lightCount);

// Every automatic value of a submitted job, resolved once from its scene:
// the image size from the camera, the photon count from the lights (a
// radiance job's 0), the light hops from the kind of cells,
// the render accelerator from the accelerator; a value a submit message
// leaves 0 or "" takes JobSettings's default. The coordinator stores the
// result and hands it to workers, which decide nothing. Resolving a
// resolved job changes nothing.
JobSettings resolveJobSettings(JobSettings settings, const SceneStore& scene);

// Checks resolved settings against their scene. Throws
// std::invalid_argument with a one-line reason.
void validateJobSettings(const JobSettings& settings, const SceneStore& scene);

// Splits spec.photons across the lights in proportion to their power
// (largest remainders, deterministic) and queues emission batches. Up to
// half a million of them: a set `stop` (SIGTERM) throws between two, so
// that the caller's transaction rolls back and the coordinator can leave.
void queuePhotonEmission(JobStore& store, uint64_t job, wire::JobSpec::Reader spec, const SceneStore& scene,
                         const std::atomic<bool>* stop = nullptr);
void queueCameraRays(JobStore& store, uint64_t job, wire::JobSpec::Reader spec, const SceneStore& scene);

}  // namespace portico
