// Photon-pass reuse. Photon maps do not depend on the camera: a job whose
// photon tables would be, bit for bit, those of an earlier job renders with
// that job's tables instead of running its own photon pass. What decides the
// tables is the store (its path and its content) and the settings the photon
// pass reads: photons, seed, the photon pass's accelerator (Embree's hits
// differ in the last bits), the photon radius (portal copies, the records'
// lattice) and the bounce limit; not the camera, image size, spp, gathering,
// light sampling or the density estimate, which only the render phase reads.
#pragma once

#include <string>

#include "common/job/job_settings.h"
#include "common/scene/store/scene_store.h"

namespace portico {

// The identity of the store's files as they are now: scene.db's bytes and
// each file's inode, size and change times. A store regenerated in place
// (new files renamed over the old) or edited gives another fingerprint.
std::string storeFingerprint(const SceneStore& scene);

// What decides a resolved job's photon tables, as text; "" for a job that
// has no photon pass (a cell or portal picture).
std::string photonPassKey(const JobSettings& resolved, const SceneStore& scene);

}  // namespace portico
