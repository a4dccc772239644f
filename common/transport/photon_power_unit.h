// The power a job's photons are stored against (PhotonFrame): the mean
// luminance one emitted photon carries, the lights' (and daylight
// emitters') total over the job's photon count.
//
// Photons are shared out among the emitters in proportion to luminance
// (photon_shares.h), so every emitted photon carries about this much, and
// a bounce only filters its colour (Russian roulette divides by the
// survival probability: scatterPhoton). A record's power is a small
// mantissa and exponent relative to it (photon_record.h). The encoder (the
// worker that deposits) and every decoder (a worker building the cell's
// map, of this job or of one that reuses its tables) compute it from the
// same scene and settings in the same operations, so it is bit-identical.
#pragma once

#include "common/job/job_settings.h"
#include "common/scene/store/scene_store.h"

namespace portico {

class DaylightEmitters;

// 1 when there is no power (no lights, all black, no photons). `daylight`:
// the job's daylight emitters when the caller has them (else they are made
// here when the job has daylight).
float photonPowerUnit(const SceneStore& scene, const JobSettings& settings, const DaylightEmitters* daylight = nullptr);

}  // namespace portico
