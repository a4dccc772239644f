// What the coordinator tells about a job: the statistics JSON written beside
// the image, the status JSON for `portico status`, and the image itself.
#pragma once

#include <nlohmann/json.hpp>

#include "common/image/linear_image.h"
#include "common/scene/store/scene_store.h"
#include "coordinator/job_store.h"
#include "coordinator/worker_registry.h"
#include "proto/wire.capnp.h"

namespace portico {

// Counters of memory, kept as peaks (JobStore::raiseCounter): each worker's
// (prefix + its name) and its --memory budget, and the coordinator's.
inline constexpr std::string_view kWorkerPeakResidentPrefix = "memory.peak_rss.worker.";
inline constexpr std::string_view kWorkerMemoryBudgetPrefix = "memory.budget.worker.";
inline constexpr std::string_view kCoordinatorPeakResidentCounter = "memory.peak_rss.coordinator";
// The coordinator's process CPU time (processCpuMicros) when the job was
// submitted and when its last Result was applied: their difference is the
// coordinator's CPU for the job, when it ran alone (the cluster model's
// cost per lease).
inline constexpr std::string_view kCoordinatorCpuAtSubmitCounter = "time.coordinator_cpu_at_submit_us";
inline constexpr std::string_view kCoordinatorCpuAtLastResultCounter = "time.coordinator_cpu_at_last_result_us";
// Photon bytes the workers wrote into the job's photon file themselves
// (deposit regions, coordinator/deposit_regions.h), and those that came in
// Results for the coordinator to write.
inline constexpr std::string_view kPhotonBytesFromWorkersCounter = "disk.photon_bytes_from_workers";
inline constexpr std::string_view kPhotonBytesFromResultsCounter = "disk.photon_bytes_from_results";
// Render phase: photon tables a worker read from the photon file itself
// (FetchPhotons.readsPhotonFile), and the bytes of those sent in replies.
inline constexpr std::string_view kPhotonTablesReadByWorkersCounter = "disk.photon_tables_read_by_workers";
inline constexpr std::string_view kPhotonBytesSentCounter = "disk.photon_bytes_sent";

nlohmann::json jobStatistics(JobStore& store, const JobRecord& job, wire::JobSpec::Reader spec);
nlohmann::json jobStatus(JobStore& store, const JobRecord& job, wire::JobSpec::Reader spec, int64_t nowMs);
// Takes out of a job's status (or its line in the jobs list) what another
// user may not see (docs/security.md): its scene store and output paths and
// its error (errors name files); what is left says how it runs.
void hideOwnersDetail(nlohmann::json& status);
nlohmann::json workersStatus(const WorkerRegistry& workers, int64_t nowMs);

// The job's film as radiance: the sum of its passes over the passes done
// (at least one), as written at the end; mid-pass, the pass under way adds
// to it, pixel range by pixel range.
LinearImage filmImage(JobStore& store, const JobRecord& job, wire::JobSpec::Reader spec);

// Resolves the film into radiance (an analysis job's: into its sensors'
// readings, analysis_results.h) and writes spec.output and spec.output +
// ".json". Creates no directory.
void writeJobOutputs(JobStore& store, const JobRecord& job, wire::JobSpec::Reader spec, const SceneStore& scene);
// The image of the job's film encoded as spec.output's extension says (an
// analysis job's CSV), for `portico fetch-image`: the client writes it.
std::string encodeJobImage(JobStore& store, const JobRecord& job, wire::JobSpec::Reader spec, const SceneStore& scene);

}  // namespace portico
