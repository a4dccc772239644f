// What `portico bench accel` and `portico bench calibrate` measure: rays like
// the renderer's (photon-like from surfaces, camera-like from an eye point),
// timed builds and timed tracing of one accelerator on one thread.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common/accel/accelerator.h"
#include "common/scene/generator/furnished_hall.h"

namespace portico::cli {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start);
// The median (the mean of the two middle values for an even count; 0 for none).
double median(std::vector<double> values);

// "1000,10k,1M" -> {1000, 10000, 1000000}; throws std::invalid_argument
// naming a bad item (counts from 12 to 4e9).
std::vector<size_t> parseTriangleCounts(const std::string& text);

// The hall's mesh, with one readable float after the last vertex (so Embree
// may share the vertices, as with a cell file). Adds that float to `hall`.
MeshView hallMesh(FurnishedHall& hall);

// Photon-like rays: a surface point chosen by area (uniform over the cell's
// surface), leaving it on the front side with a cosine-distributed
// direction, from the renderer's own offset off the surface
// (offsetAlongNormal: 2e-5 of the point's largest coordinate, at least 20 um).
std::vector<Ray> photonRays(const MeshView& mesh, size_t count, uint64_t seed);
// Camera-like rays: from the hall's eye point (above the furniture), looking
// diagonally across the hall and 30 degrees down, through a 16:9 grid of
// directions spanning 100 degrees horizontally; row by row.
std::vector<Ray> cameraRays(const FurnishedHall& hall, size_t count);

struct TraceResult {
  double mraysPerSecond = 0;
  uint64_t hits = 0;
  uint64_t differing = 0;  // rays whose hit differs from the reference structure's
  std::vector<Hit> hitList;
};

// A warm-up pass over up to 10k rays, then the median of `runs` passes timed
// by the thread's CPU time.
TraceResult traceRays(const Accelerator& accelerator, const std::vector<Ray>& rays, uint32_t runs);
// The same for several structures, their timed passes taken in turn (each
// after a short warm-up of its own): a machine whose load changes over
// seconds slows every structure alike, so their ratios hold where one
// structure's passes after another's would not.
std::vector<TraceResult> traceRaysInterleaved(const std::vector<const Accelerator*>& accelerators,
                                              const std::vector<Ray>& rays, uint32_t runs);
// Builds `runs` times (once when a build takes over 20 s) and keeps the last;
// medianMs: the median build's CPU time over every thread of the process.
std::unique_ptr<Accelerator> timedBuild(const AcceleratorSpec& spec, const MeshView& mesh, uint32_t runs,
                                        double& medianMs);

}  // namespace portico::cli
