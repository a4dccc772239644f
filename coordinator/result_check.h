// What a Result must satisfy before the coordinator applies it: it adds up
// against the lease it answers, and its film values are possible.
//
// Why. A worker is trusted to trace, not to be right: a worker with a bug,
// bad memory or another build, or a peer that holds a worker's key, could
// send a Result that reports less work than its lease held (photons never
// emitted), loses rays (crossings dropped) or holds film values no tracer
// makes (negative, beyond the film's range). Applied, such a Result changes
// the image and the job still ends "done". Refused, its lease is traced
// again elsewhere (Coordinator::refuseResult) and nothing of it is kept.
//
// What is checked (docs/security.md, "What a Result must satisfy"), each in
// time linear in the Result's size, reading no more than applying it reads:
// - photon lease: photons.emitted equals the photons its emission batches
//   asked for; every photon it started (emitted, or received as a ray) ended
//   once: absorbed + escaped + rays handed on (its crossings) + rays.invalid;
//   no more deposit records than photons.deposits + photons.portal_copies;
//   no film.
// - render lease: rays.camera = its camera batches' pixels x spp (sensor
//   batches' sensors x spp); sensors.measured = its sensors; every ray
//   started ended once: camera + emission + received + shadow + gather =
//   rays.finished + rays.invalid + rays handed on; rays handed on <=
//   rays.crossings; rays.invalid <= rays received; no deposits; film value
//   in [0, the film's range] on a pixel of the image; film.out_of_range 0.
// - every counter is >= 0.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

#include "proto/wire.capnp.h"

namespace portico {

// A Result that does not add up, or holds impossible values: refused.
struct BadResultError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// What a lease asked for, summed over its batches (more cells' included)
// as they are copied into its Assign.
struct LeaseExpectation {
  int phase = 0;                // 0: photons, 1: render
  int64_t photonsToEmit = 0;    // EmitRange counts
  int64_t raysIn = 0;           // rays of its ray batches
  int64_t cameraSamples = 0;    // CameraRange pixels (and sensors) x spp
  int64_t sensors = 0;          // sensors of its sensor batches
  void add(wire::RayBatch::Reader batch, uint32_t spp);
};

// Throws BadResultError naming the first thing that does not add up.
// `expected` is null where the lease's batches are not known (a lease
// opened before the coordinator restarted is never answered: its Result is
// dropped before this): then only what needs no lease is checked.
void checkResultCounts(const LeaseExpectation* expected, int phase, wire::Result::Reader result);

// One film value of a render Result: a pixel of the image, each channel
// within [0, kFilmMaxSum]. Called as the film is summed (no second pass).
void checkFilmValue(wire::PixelSum::Reader pixel, uint64_t pixelCount);

}  // namespace portico
