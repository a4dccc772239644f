// What a lease did, counted. Summed per job by the coordinator; the photon
// counters prove conservation: emitted == absorbed + escaped + still queued.
#pragma once

#include <cstdint>
#include <string_view>
#include <utility>
#include <vector>

namespace portico {

// A Result's counter of the lease's time on its worker, in microseconds
// (loads included); the coordinator reads each worker's speed from it.
inline constexpr std::string_view kLeaseTimeCounter = "time.lease_us";
// Of that time, its tracing thread's CPU, and its time runnable but waiting
// for a core (absent where the kernel does not count it): the rest it was
// blocked. The cluster model reads a lease's own cost from them.
inline constexpr std::string_view kLeaseCpuCounter = "time.lease_cpu_us";
inline constexpr std::string_view kLeaseRunQueueCounter = "time.lease_run_queue_us";
// Its cells loaded: their time on the worker (read and accelerator build,
// microseconds) and their triangles; the coordinator reads each worker's
// cost of loading a cell from them.
inline constexpr std::string_view kLoadTimeCounter = "time.load_us";
inline constexpr std::string_view kTrianglesLoadedCounter = "cells.triangles_loaded";

// The worker's peak resident memory so far (VmHWM, bytes): the coordinator
// keeps the largest per worker and job, not a sum.
inline constexpr std::string_view kPeakResidentCounter = "memory.peak_rss_bytes";

// Contributions a lease could not add to its film (film.h): any fails the job.
inline constexpr std::string_view kFilmOutOfRangeCounter = "film.out_of_range";

struct TraceCounters {
  int64_t photonsEmitted = 0;
  int64_t photonDeposits = 0;
  int64_t photonsAbsorbed = 0;    // ended by Russian roulette, an emitter or the depth cap
  int64_t photonsEscaped = 0;     // left a cell where no portal was
  int64_t photonCrossings = 0;
  int64_t photonCopies = 0;       // deposits copied to a neighbour near a portal
  int64_t cameraRays = 0;         // shaded camera samples (an analysis job's: sensor samples)
  int64_t sensorsMeasured = 0;    // an analysis job's sensors, each with all its samples
  int64_t emissionRays = 0;       // camera rays that add only emitted light (cell_kernel.h)
  int64_t shadowRays = 0;
  int64_t gatherRays = 0;
  int64_t shortGathers = 0;       // gather hits lit by shadow rays and a gather ray of their own
  int64_t shadowBlocked = 0;
  int64_t shadowReached = 0;
  int64_t rayCrossings = 0;       // camera and shadow rays handed to a neighbour cell
  int64_t raysEscaped = 0;        // camera and shadow rays that left the building
  int64_t raySegments = 0;        // rays traced through one cell (all kinds)
  int64_t raysInvalid = 0;        // malformed rays received and dropped
  // Render rays (camera, emission, shadow, gather) that ended in this lease:
  // shaded, read, blocked, reached their light or the sky, escaped. With the
  // rays handed on, they balance the rays started (result_check.h):
  // camera + emission + received + shadow + gather = finished + invalid + handed on.
  int64_t raysFinished = 0;
  int64_t nonFiniteContributions = 0;
  int64_t filmOutOfRange = 0;     // contributions refused: a pixel's sum would leave the film's range

  // Stable names used on the wire, in jobs.db and in the statistics JSON.
  std::vector<std::pair<std::string_view, int64_t>> named() const {
    return {{"photons.emitted", photonsEmitted},   {"photons.deposits", photonDeposits},
            {"photons.absorbed", photonsAbsorbed}, {"photons.escaped", photonsEscaped},
            {"photons.crossings", photonCrossings}, {"photons.portal_copies", photonCopies},
            {"rays.camera", cameraRays},           {"rays.emission", emissionRays},
            {"sensors.measured", sensorsMeasured},
            {"rays.gather", gatherRays},           {"rays.gather_short", shortGathers},
            {"rays.shadow", shadowRays},           {"rays.shadow_blocked", shadowBlocked},
            {"rays.shadow_reached", shadowReached}, {"rays.crossings", rayCrossings},
            {"rays.escaped", raysEscaped},         {"rays.traced", raySegments},
            {"rays.invalid", raysInvalid},         {"rays.finished", raysFinished},
            {"film.non_finite", nonFiniteContributions},
            {kFilmOutOfRangeCounter, filmOutOfRange}};
  }
};

}  // namespace portico
