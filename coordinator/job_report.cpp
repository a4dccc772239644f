#include "coordinator/job_report.h"

#include <cmath>
#include <fmt/format.h>

#include <stdlib.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "common/analysis/luminance_image.h"
#include "common/image/image_writer.h"
#include "common/transport/trace_counters.h"
#include "common/util/atomic_file.h"
#include "coordinator/analysis_results.h"
#include "coordinator/analysis_sensors.h"
#include "coordinator/luminance_output.h"
#include "coordinator/render_passes.h"

namespace portico {

namespace {
constexpr size_t kListedCells = 16;   // per worker, in status

int64_t get(const std::map<std::string, int64_t>& counters, const std::string& name) {
  auto it = counters.find(name);
  return it == counters.end() ? 0 : it->second;
}

// The structures built, from the workers' "accel.built.<spec>" and
// "accel.cell.<id>.<spec>" counters: builds per spec, and per cell the specs
// it was built with (more than one when `auto` rebuilt it, or when several
// workers loaded it with different choices).
void addAcceleratorChoices(const std::map<std::string, int64_t>& counters, nlohmann::json& stats, bool perCell) {
  nlohmann::json builds = nlohmann::json::object(), cells = nlohmann::json::object();
  const std::string builtPrefix = "accel.built.", cellPrefix = "accel.cell.";
  for (const auto& [name, value] : counters) {
    if (name.rfind(builtPrefix, 0) == 0) {
      builds[name.substr(builtPrefix.size())] = value;
    } else if (perCell && name.rfind(cellPrefix, 0) == 0) {
      const std::string rest = name.substr(cellPrefix.size());
      const size_t dot = rest.find('.');
      if (dot == std::string::npos) continue;
      cells[rest.substr(0, dot)].push_back(rest.substr(dot + 1));
    }
  }
  stats["accelerators"] = builds;
  if (perCell) stats["cell_accelerators"] = cells;
}

// Cell reloads, from the same per-cell counters (one per load, whatever the
// structure): how many cells were loaded once, twice, ..., by all workers
// over both phases together.
void addCellLoads(const std::map<std::string, int64_t>& counters, nlohmann::json& cellStats) {
  std::map<uint32_t, int64_t> loadsOfCell;
  const std::string cellPrefix = "accel.cell.";
  for (auto it = counters.lower_bound(cellPrefix); it != counters.end() && it->first.rfind(cellPrefix, 0) == 0; ++it)
    loadsOfCell[uint32_t(std::strtoul(it->first.c_str() + cellPrefix.size(), nullptr, 10))] += it->second;
  std::map<int64_t, int64_t> cellsByLoads;
  int64_t loads = 0;
  for (const auto& [cell, n] : loadsOfCell) {
    ++cellsByLoads[n];
    loads += n;
  }
  nlohmann::json histogram = nlohmann::json::object();
  for (const auto& [n, cellCount] : cellsByLoads) histogram[std::to_string(n)] = cellCount;
  cellStats["distinct_loaded"] = loadsOfCell.size();
  cellStats["reloads"] = loads - int64_t(loadsOfCell.size());
  cellStats["cells_by_loads"] = histogram;
}

// Peak resident memory: the coordinator's, and each worker's with its
// --memory budget, as the Results reported them (VmHWM: the process's peak
// since it started, so a worker that served earlier jobs shows theirs too).
nlohmann::json memoryStatistics(const std::map<std::string, int64_t>& counters) {
  nlohmann::json workers = nlohmann::json::object();
  const auto perWorker = [&](std::string_view prefix, const char* key) {
    const std::string p(prefix);
    for (auto it = counters.lower_bound(p); it != counters.end() && it->first.rfind(p, 0) == 0; ++it)
      workers[it->first.substr(p.size())][key] = it->second;
  };
  perWorker(kWorkerPeakResidentPrefix, "peak_rss_bytes");
  perWorker(kWorkerMemoryBudgetPrefix, "budget_bytes");
  int64_t workersPeak = 0;
  for (const auto& [name, w] : workers.items()) workersPeak = std::max(workersPeak, w.value("peak_rss_bytes", int64_t(0)));
  return {{"coordinator_peak_rss_bytes", get(counters, std::string(kCoordinatorPeakResidentCounter))},
          {"workers_peak_rss_bytes", workersPeak},
          {"workers", workers}};
}
// Passes done, each one's error estimate and end (ms of render), the
// settings that stop them and why they stopped (null while they go on).
nlohmann::json renderPassStatistics(JobStore& store, const JobRecord& job, wire::JobSpec::Reader spec) {
  const RenderProgress progress = loadRenderProgress(store.database(), job.id);
  nlohmann::json estimates = nlohmann::json::array(), ends = nlohmann::json::array();
  for (const RenderPassRecord& pass : progress.passes) {
    estimates.push_back(pass.errorEstimate ? nlohmann::json(*pass.errorEstimate) : nlohmann::json());
    ends.push_back(pass.finishedMs - job.phaseStartedMs);
  }
  nlohmann::json passes = {{"done", progress.passesDone()},
                           {"max_passes", spec.getMaxPasses()},
                           {"error_estimates", estimates},
                           {"ends_ms", ends}};
  passes["current"] = job.state == JobState::Render ? nlohmann::json(progress.passesStarted) : nlohmann::json();
  passes["error_estimate"] = estimates.empty() ? nlohmann::json() : estimates.back();
  passes["target_error"] =
      spec.getTargetError().isValue() ? nlohmann::json(spec.getTargetError().getValue()) : nlohmann::json();
  passes["time_limit_s"] =
      spec.getTimeLimit().isSeconds() ? nlohmann::json(spec.getTimeLimit().getSeconds()) : nlohmann::json();
  passes["stopped"] = progress.stopReason.empty() ? nlohmann::json() : nlohmann::json(progress.stopReason);
  return passes;
}

// The job's sun and sky as resolved (a --sun-time's azimuth and elevation
// too); null without daylight.
nlohmann::json daylightSettings(wire::JobSpec::Reader spec) {
  if (!spec.hasDaylight()) return nullptr;
  const auto d = spec.getDaylight();
  const auto sky = d.getSky();
  nlohmann::json daylight = {{"sky", sky == wire::SkyKind::UNIFORM    ? "uniform"
                                     : sky == wire::SkyKind::PREETHAM ? "preetham"
                                     : sky == wire::SkyKind::OVERCAST ? "overcast"
                                                                      : "none"},
                             {"turbidity", d.getTurbidity()},
                             {"sun", d.getSun()}};
  if (d.getSun()) {
    daylight["sun_azimuth"] = d.getSunAzimuth();
    daylight["sun_elevation"] = d.getSunElevation();
  }
  return daylight;
}
}  // namespace

namespace {
// The statistics from the job's counters, read once by the caller; a
// status reply leaves out the accelerators of each cell (one entry per cell:
// the statistics file has them), so that a poll costs little on a tower.
nlohmann::json statisticsOf(JobStore& store, const JobRecord& job, wire::JobSpec::Reader spec,
                            const std::map<std::string, int64_t>& counters, bool perCell) {
  nlohmann::json stats;
  stats["job"] = job.id;
  stats["state"] = std::string(toString(job.state));
  if (!job.error.empty()) stats["error"] = job.error;
  stats["settings"] = {{"store", spec.getStore().cStr()},   {"output", spec.getOutput().cStr()},
                       {"photons", spec.getPhotons()},      {"spp", spec.getSpp()},
                       {"seed", spec.getSeed()},            {"accel", spec.getAccel().cStr()},
                       {"render_accel", spec.getRenderAccel().cStr()},
                       {"width", spec.getWidth()},          {"height", spec.getHeight()},
                       {"light_samples", spec.getLightSamples()}, {"photon_k", spec.getPhotonK()},
                       {"photon_radius", spec.getPhotonRadius()}, {"gather", spec.getGather()},
                       {"light_hops", spec.getLightHops()},
                       {"light_sampling", spec.getLightSampling() == wire::LightSampling::SCAN ? "scan" : "tree"},
                       {"irradiance", spec.getIrradiance() == wire::Irradiance::KNN ? "knn" : "precomputed"},
                       {"aov", spec.getAov() == wire::Aov::CELLS     ? "cells"
                               : spec.getAov() == wire::Aov::PORTALS ? "portals"
                               : spec.hasLuminance()                 ? "luminance"
                                                                     : "radiance"},
                       {"daylight", daylightSettings(spec)}};
  // A job that reused an earlier job's photon pass shows that pass's photons.
  std::map<std::string, int64_t> lenderCounters;
  if (job.photonSource) lenderCounters = store.counters(job.photonSource);
  const auto& photonCounters = job.photonSource ? lenderCounters : counters;
  stats["photons"] = {{"emitted", get(photonCounters, "photons.emitted")},
                      {"deposits", get(photonCounters, "photons.deposits")},
                      {"absorbed", get(photonCounters, "photons.absorbed")},
                      {"escaped", get(photonCounters, "photons.escaped")},
                      {"crossings", get(photonCounters, "photons.crossings")},
                      {"portal_copies", get(photonCounters, "photons.portal_copies")},
                      {"queued", store.queuedRays(job.photonJob(), 0)}};
  // Whose photon pass it rendered with, and the photons its own leases
  // emitted (0 when it reused one).
  stats["photon_pass"] = {{"reused_from_job", job.photonSource ? nlohmann::json(job.photonSource) : nlohmann::json()},
                          {"photons_emitted_by_this_job", get(counters, "photons.emitted")}};
  const int64_t camera = get(counters, "rays.camera");
  const int64_t crossings = get(counters, "rays.crossings");
  stats["rays"] = {{"camera", camera},
                   {"emission", get(counters, "rays.emission")},
                   {"shadow", get(counters, "rays.shadow")},
                   {"gather", get(counters, "rays.gather")},
                   {"gather_short", get(counters, "rays.gather_short")},
                   {"shadow_blocked", get(counters, "rays.shadow_blocked")},
                   {"shadow_reached", get(counters, "rays.shadow_reached")},
                   {"escaped", get(counters, "rays.escaped")},
                   {"traced", get(counters, "rays.traced")},
                   {"crossings", crossings},
                   {"forwarded", get(counters, "rays.forwarded")},
                   {"crossings_per_camera_ray", camera ? double(crossings) / camera : 0.0},
                   {"invalid", get(counters, "rays.invalid")},
                   {"queued", store.queuedRays(job.id, 1)}};
  stats["cells"] = {{"loaded", get(counters, "cells.loaded")},
                    {"cache_hits", get(counters, "cells.cache_hits")},
                    {"bytes_read", get(counters, "cells.bytes_read")},
                    {"triangles_loaded", get(counters, std::string(kTrianglesLoadedCounter))},
                    {"photon_maps_built", get(counters, "photon_maps.built")}};
  addCellLoads(counters, stats["cells"]);
  stats["memory"] = memoryStatistics(counters);
  // The job's own files (its photons and queued rays) and jobs.db, which
  // every job shares.
  const JobStore::JobFileBytes files = store.jobFileBytes(job.id);
  stats["disk"] = {{"photon_file_bytes", files.photons},
                   {"batch_file_bytes", files.batches},
                   {"job_bytes", files.photons + files.batches},
                   {"photon_bytes_from_workers", get(counters, std::string(kPhotonBytesFromWorkersCounter))},
                   {"photon_bytes_from_results", get(counters, std::string(kPhotonBytesFromResultsCounter))},
                   {"photon_tables_read_by_workers", get(counters, std::string(kPhotonTablesReadByWorkersCounter))},
                   {"photon_bytes_sent", get(counters, std::string(kPhotonBytesSentCounter))},
                   {"jobs_db_bytes", store.databaseBytes()}};
  stats["leases"] = get(counters, "leases.completed");
  // Photon-pass leases that carried more cells than their own, and how many.
  stats["lease_extra_cells"] = get(counters, "leases.extra_cells");
  // Photon passes run again because a photon file was found damaged.
  stats["photon_pass_restarts"] = get(counters, JobStore::kPhotonPassRestarts);
  const int64_t cpuAtSubmit = get(counters, std::string(kCoordinatorCpuAtSubmitCounter));
  const int64_t cpuAtLastResult = get(counters, std::string(kCoordinatorCpuAtLastResultCounter));
  const int64_t coordinatorCpuMicros =
      cpuAtSubmit > 0 && cpuAtLastResult > cpuAtSubmit ? cpuAtLastResult - cpuAtSubmit : 0;
  const int64_t leasesCompleted = get(counters, "leases.completed");
  stats["time_ms"] = {{"photons", get(counters, "time.photons_ms")},
                      // The coordinator's CPU from submit to the last Result
                      // (other jobs' too, when several run at once).
                      {"coordinator_cpu", coordinatorCpuMicros / 1000},
                      {"render", get(counters, "time.render_ms")},
                      {"accelerator_build", std::llround(get(counters, "time.accel_build_us") * 1e-3)},
                      // Cell loads: reading, validating and building, all workers added up.
                      {"cell_loads", std::llround(get(counters, std::string(kLoadTimeCounter)) * 1e-3)},
                      // The workers' time inside leases, all workers added up:
                      // against the phases' time x workers, how busy they were.
                      {"leases", std::llround(get(counters, std::string(kLeaseTimeCounter)) * 1e-3)},
                      {"total", (job.finishedMs ? job.finishedMs : job.phaseStartedMs) - job.createdMs}};
  // That CPU over the job's leases: what one lease costs the coordinator,
  // every thread of it (statements, commits, messages, files, status polls).
  stats["coordinator_cpu_per_lease_us"] = leasesCompleted > 0 ? coordinatorCpuMicros / leasesCompleted : 0;
  stats["film"] = {{"non_finite_contributions", get(counters, "film.non_finite")}};
  addAcceleratorChoices(counters, stats, perCell);
  stats["render_passes"] = renderPassStatistics(store, job, spec);
  if (spec.hasAnalysis())
    stats["analysis"] = {{"sensors", spec.getAnalysis().getSensors()},
                         {"outside_cells", sensorsOutsideCells(store.jobSensors(job.id))},
                         {"measured", get(counters, "sensors.measured")},
                         {"samples_per_sensor", spec.getSpp()},
                         {"daylight_factor", spec.getAnalysis().getDaylightFactor()}};
  return stats;
}

}  // namespace

nlohmann::json jobStatistics(JobStore& store, const JobRecord& job, wire::JobSpec::Reader spec) {
  return statisticsOf(store, job, spec, store.counters(job.id), true);
}

void hideOwnersDetail(nlohmann::json& status) {
  if (status.contains("error") && !status["error"].get<std::string>().empty()) status["error"] = "(another user's job)";
  if (status.contains("settings")) {
    status["settings"].erase("store");
    status["settings"].erase("output");
  }
  // Why it waits, without the path an unreadable store's reason names.
  if (status.contains("waiting"))
    for (auto& reason : status["waiting"])
      if (reason.get<std::string>().rfind("store cannot be read", 0) == 0) reason = "store cannot be read";
}

nlohmann::json jobStatus(JobStore& store, const JobRecord& job, wire::JobSpec::Reader spec, int64_t nowMs) {
  const auto counters = store.counters(job.id);
  nlohmann::json status = statisticsOf(store, job, spec, counters, false);
  const int64_t photonsDone = status["photons"]["absorbed"].get<int64_t>() + status["photons"]["escaped"].get<int64_t>();
  // The passes started so far (the statistics' own count: the one being
  // rendered, else those done, at least one): a job in passes does not
  // know how many it will take.
  const auto& passes = status["render_passes"];
  const uint32_t passesCounted = std::max<uint32_t>(
      {1u, passes["current"].is_number() ? passes["current"].get<uint32_t>() : 0u, passes["done"].get<uint32_t>()});
  // An analysis job's camera samples are those of its sensors inside cells.
  const int64_t samples =
      (spec.hasAnalysis() ? status["analysis"]["sensors"].get<int64_t>() - status["analysis"]["outside_cells"].get<int64_t>()
                          : int64_t(spec.getWidth()) * spec.getHeight()) *
      spec.getSpp() * passesCounted;
  status["progress"] = {{"photons_done", photonsDone},
                        {"photons_total", spec.getPhotons()},
                        {"camera_rays_done", get(counters, "rays.camera")},
                        {"camera_rays_total", samples}};
  // Fraction of the whole job: photons weigh as much as camera samples.
  const double fraction =
      job.state == JobState::Done
          ? 1.0
          : 0.5 * double(photonsDone) / std::max<int64_t>(1, spec.getPhotons()) +
                0.5 * double(get(counters, "rays.camera")) / std::max<int64_t>(1, samples);
  status["progress"]["fraction"] = fraction;
  // An ended job's time is its own, not the time since it was submitted.
  const int64_t endMs = isActive(job.state) || job.finishedMs == 0 ? nowMs : job.finishedMs;
  const double elapsed = double(endMs - job.createdMs) / 1000.0;
  status["elapsed_s"] = elapsed;
  status["rays_per_s"] = elapsed > 0 ? double(get(counters, "rays.traced")) / elapsed : 0.0;
  if (isActive(job.state) && fraction > 0.01 && spec.getMaxPasses() == 1) status["eta_s"] = elapsed * (1.0 - fraction) / fraction;
  nlohmann::json pending = nlohmann::json::array();
  for (const auto& [cell, work] : store.pendingWorkByCell(job.id, phaseOf(job.state), 8))
    pending.push_back({{"cell", cell}, {"work", work}});
  status["pending_cells"] = pending;
  status["priority"] = job.priority;
  status["required_tags"] = job.requiredTags;
  return status;
}

nlohmann::json workersStatus(const WorkerRegistry& workers, int64_t nowMs) {
  nlohmann::json list = nlohmann::json::array();
  for (const auto& [identity, w] : workers) {
    // The most recently leased first, at most kListedCells of them.
    nlohmann::json cells = nlohmann::json::array();
    for (auto it = w.cells.cells().rbegin(); it != w.cells.cells().rend() && cells.size() < kListedCells; ++it)
      cells.push_back({{"job", it->job}, {"cell", it->cell}});
    nlohmann::json current = nlohmann::json::array();
    for (const auto& [lease, inFlight] : w.leases)
      current.push_back({{"lease", lease}, {"job", inFlight.job}, {"cell", inFlight.cell},
                         {"phase", inFlight.phase == 0 ? "photons" : "render"}});
    list.push_back({{"name", w.name},
                    {"tags", w.tags},
                    {"idle", w.idle()},
                    {"leases", w.leases.size()},
                    {"leases_in_flight", current},
                    {"leases_done", w.leasesDone},
                    {"cores", w.cores},
                    {"memory_budget_bytes", w.memoryBytes},
                    {"peak_rss_bytes", w.peakResidentBytes},
                    {"last_seen_ms_ago", nowMs - w.lastSeenMs},
                    {"cells_held", w.cells.size()},
                    {"cells", cells}});
    // Its leases were taken back: it heartbeats, but its tracing does not move.
    if (w.stalledSinceMs != 0) list.back()["stalled"] = w.stallReason;
  }
  return list;
}

LinearImage filmImage(JobStore& store, const JobRecord& job, wire::JobSpec::Reader spec) {
  const uint32_t width = spec.getWidth(), height = spec.getHeight();
  const uint64_t pixels = uint64_t(width) * height;
  const std::vector<FixedRgb> film = store.film(job.id, pixels);
  // The film holds the sum of the passes done: the image is their average
  // (one pass: x / 1.0 is x, the same bits as ever).
  const double passes = std::max<uint32_t>(1, loadRenderProgress(store.database(), job.id).passesDone());
  const auto average = [passes](int64_t sum) { return static_cast<float>(static_cast<double>(sum) / kFilmScale / passes); };
  LinearImage image;
  image.width = width;
  image.height = height;
  image.rgb.resize(pixels * 3);
  for (uint64_t p = 0; p < pixels; ++p) {
    image.rgb[3 * p + 0] = average(film[p].r);
    image.rgb[3 * p + 1] = average(film[p].g);
    image.rgb[3 * p + 2] = average(film[p].b);
  }
  return image;
}

void writeJobOutputs(JobStore& store, const JobRecord& job, wire::JobSpec::Reader spec, const SceneStore& scene) {
  // The directory was checked at submit; it is never created here, on
  // behalf of whoever submitted.
  const std::string output = spec.getOutput().cStr();
  nlohmann::json luminance;
  if (spec.hasAnalysis())
    writeAnalysisOutputs(analysisResults(store, job, spec, scene), output);
  else if (spec.hasLuminance())
    luminance = writeLuminanceOutputs(output, filmImage(store, job, spec), spec.getLuminance());
  else
    writeImage(output, filmImage(store, job, spec), spec.getExposure());
  nlohmann::json statistics = jobStatistics(store, job, spec);
  if (!luminance.is_null()) statistics["luminance"] = luminance;
  const std::string statsPath = output + ".json";
  writeFileAtomically(statsPath, statistics.dump(2) + "\n");
}

std::string encodeJobImage(JobStore& store, const JobRecord& job, wire::JobSpec::Reader spec, const SceneStore& scene) {
  namespace fs = std::filesystem;
  if (spec.hasAnalysis()) return analysisCsv(analysisResults(store, job, spec, scene));
  // OpenImageIO writes files: one in a private directory, read back and removed.
  std::string pattern = (fs::temp_directory_path() / "portico-image-XXXXXX").string();
  if (!::mkdtemp(pattern.data()))
    throw std::runtime_error(fmt::format("cannot create a temporary directory in {}: {}",
                                         fs::temp_directory_path().string(), std::strerror(errno)));
  const fs::path file = fs::path(pattern) / ("image" + fs::path(spec.getOutput().cStr()).extension().string());
  std::string bytes;
  try {
    // A luminance job's image is its cd/m^2 (its false-colour picture stays beside the job's output).
    const LinearImage film = filmImage(store, job, spec);
    writeImage(file.string(), spec.hasLuminance() ? luminanceImage(film) : film, spec.getExposure());
    std::ifstream in(file, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  } catch (...) {
    fs::remove_all(pattern);
    throw;
  }
  fs::remove_all(pattern);
  return bytes;
}

}  // namespace portico
