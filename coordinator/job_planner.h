// Turns a submitted job into its first queued work, and a finished photon
// phase into camera work: compact generator batches (EmitRange,
// CameraRange) that workers expand themselves.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>

#include "common/scene/store/scene_store.h"
#include "coordinator/job_store.h"
#include "proto/wire.capnp.h"

namespace portico {

// Photons handed to one emission batch, camera samples to one camera batch:
// each about a tenth to a half of a second of tracing on one core.
constexpr uint32_t kPhotonsPerEmitBatch = 20000;
constexpr uint64_t kMostEmitBatches = 50000;   // a billion photons; beyond, batches grow
constexpr uint32_t kSamplesPerCameraBatch = 16384;

// Checks a spec against its scene, filling defaults (image size from the
// camera). Throws std::invalid_argument with a one-line reason.
void validateSpec(wire::JobSpec::Builder spec, const SceneStore& scene);

// Splits spec.photons across the lights in proportion to their power
// (largest remainders, deterministic) and queues emission batches. Up to
// half a million of them: a set `stop` (SIGTERM) throws between two, so
// that the caller's transaction rolls back and the coordinator can leave.
void queuePhotonEmission(JobStore& store, uint64_t job, wire::JobSpec::Reader spec, const SceneStore& scene,
                         const std::atomic<bool>* stop = nullptr);
void queueCameraRays(JobStore& store, uint64_t job, wire::JobSpec::Reader spec, const SceneStore& scene);

}  // namespace portico
