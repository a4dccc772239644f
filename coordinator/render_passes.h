// The render phase in passes (progressive rendering). Each pass queues the
// job's camera rays again (queueCameraRays) and renders its `spp` samples
// per pixel with its own seed; workers add every pass to the one film, so
// the film holds the sum of the passes and the image is their average. After
// each pass the coordinator writes the image and estimates its error from
// the passes' spread (pass_error.h); the job stops after the first pass
// whose estimate is at most --target-error, before a pass predicted to end
// past --time-limit seconds of render, or after --max-passes passes. A job
// without a target or time limit renders one pass with its own seed: the
// image it always had.
//
// jobs.db keeps the pass count, each pass's end and estimate, the stop
// reason, and per 16x16 block the statistics of the passes so far
// (render_progress and render_passes, JobStore schema 7), all written with
// the pass's end in one transaction: a coordinator killed at any moment
// resumes the pass in progress, with its seed.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "coordinator/job_store.h"
#include "proto/wire.capnp.h"

namespace portico {

// Why a job's render passes ended.
enum class PassStop { None, TargetMet, TimeLimit, MaxPasses };
const char* toString(PassStop stop);   // "target_met", "time_limit", "max_passes"

struct RenderPassRecord {
  uint32_t pass = 0;                    // 1, 2, ...
  int64_t finishedMs = 0;               // wall clock
  std::optional<double> errorEstimate;  // none before two passes
};

struct RenderProgress {
  uint32_t passesStarted = 1;           // the pass being rendered, once the render phase began
  std::vector<RenderPassRecord> passes; // finished ones, in order
  std::string stopReason;               // toString(PassStop); "" while passes go on
  uint32_t passesDone() const { return uint32_t(passes.size()); }
};

// The seed of render pass `index` (0 for the first): the job's own for the
// first pass, so that a job of one pass is the job it always was; a mix of
// the seed and the index for the others.
uint64_t passSeed(uint64_t seed, uint32_t index);

// What jobs.db says of the job's passes (a job without a row: one pass started).
RenderProgress loadRenderProgress(sql::Database& db, uint64_t job);

// After the passes that ended at `passEndsMs` (ms of render, one per
// finished pass, the last just now): another pass, or why not.
PassStop stopAfterPass(wire::JobSpec::Reader spec, std::optional<double> errorEstimate,
                       const std::vector<int64_t>& passEndsMs);

struct PassEnd {
  uint32_t pass = 0;                    // the pass that ended
  std::optional<double> errorEstimate;
  PassStop stop = PassStop::None;       // None: pass `pass + 1` is to be queued
  bool recordedBefore = false;          // a coordinator restarted after the last pass's end was recorded
};

// Called, in the caller's transaction, when the render phase has no work
// left: records the pass that ended (its error estimate from the film) and
// either counts the next one as started (the caller queues its camera rays)
// or records why the passes end.
PassEnd endRenderPass(JobStore& store, const JobRecord& job, wire::JobSpec::Reader spec, int64_t nowMs);

}  // namespace portico
