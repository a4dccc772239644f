#include "coordinator/cli/bench/bench_cluster.h"

#include <fmt/format.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <numeric>
#include <optional>
#include <set>
#include <stdexcept>

#include "common/accel/accelerator.h"
#include "common/net/job_spec_wire.h"
#include "common/net/message.h"
#include "common/scene/store/cell_geometry.h"
#include "common/scene/store/scene_store.h"
#include "common/util/size_parse.h"
#include "common/util/temporary_directory.h"
#include "coordinator/cli/bench/coordinator_cost_table.h"
#include "coordinator/cluster_model.h"
#include "coordinator/job_report.h"
#include "coordinator/job_store.h"

namespace portico::cli {

namespace {
namespace fs = std::filesystem;

// A finished job as the model reads it, and what it measured.
struct MeasuredJob {
  std::string name;               // JOBS_DB:JOB
  ClusterRecord record;
  size_t workers = 0;             // distinct workers in its lease log
  uint64_t workerMemoryBytes = 0;
  double photonSeconds = 0, renderSeconds = 0;
  // The cores its threads had: its workers' CPU in leases and the
  // coordinator's, over its time (0: CPU not recorded).
  double coresHad = 0;
  // What a loaded cell takes in a worker's cache per byte of its file, with
  // the photon pass's structure and the render's.
  double cachedBytesPerFileByte[2] = {3, 3};
};

// The structures a job's leases built: the photon pass's, and the render's
// ("" is bvh with the grid, else the photon pass's; `auto` taken as the grid).
std::pair<std::string, std::string> structuresOf(const JobSettings& settings) {
  const std::string photons = settings.accel == "auto" ? "grid" : settings.accel;
  std::string render = settings.renderAccel.empty() ? (photons == "grid" ? "bvh" : photons) : settings.renderAccel;
  if (render == "auto") render = "bvh";
  return {photons, render};
}

// A loaded cell's bytes in a worker's cache (LoadedCell::bytes: its mapped
// geometry and its accelerator) per byte of its file, measured on a few of
// the store's cells, from the smallest to the largest.
double cachedBytesPerFileByte(const SceneStore& store, const std::string& spec) {
  const auto& cells = store.cells();
  if (cells.empty()) return 3;
  std::vector<uint32_t> bySize(cells.size());
  std::iota(bySize.begin(), bySize.end(), 0u);
  std::sort(bySize.begin(), bySize.end(),
            [&](uint32_t a, uint32_t b) { return cells[a].byteCount < cells[b].byteCount; });
  constexpr size_t kSamples = 8;
  std::set<uint32_t> sample;
  for (size_t k = 0; k < kSamples; ++k) sample.insert(bySize[(bySize.size() - 1) * k / (kSamples - 1)]);
  const AcceleratorSpec parsed = parseAcceleratorSpec(spec);
  double cached = 0, file = 0;
  for (uint32_t id : sample) {
    const auto geometry = CellGeometry::load(store.cellPath(id), id, store.materials().size());
    const auto accelerator = buildAccelerator(parsed, geometry->mesh());
    cached += double(geometry->bytes() + accelerator->stats().bytes);
    file += double(cells[id].byteCount);
  }
  return file > 0 ? cached / file : 3;
}

// The coordinator's time between the photon pass's last Result and the
// render's first lease (0 where the log cannot tell).
double phaseChangeSeconds(const std::vector<LeaseLogEntry>& leases) {
  int64_t lastPhotonResult = 0, firstRenderSent = 0;
  for (const LeaseLogEntry& lease : leases) {
    if (lease.phase == 0) lastPhotonResult = std::max(lastPhotonResult, lease.resultMs);
    else if (lease.sentMs > 0 && (firstRenderSent == 0 || lease.sentMs < firstRenderSent)) firstRenderSent = lease.sentMs;
  }
  if (lastPhotonResult == 0 || firstRenderSent == 0) return 0;
  return double(std::max<int64_t>(0, firstRenderSent - lastPhotonResult)) * 1e-3;
}

// The photon pass's time before its first lease: its measured time less the
// span of its leases (0 where the log cannot tell).
double phaseStartSeconds(const std::vector<LeaseLogEntry>& leases, double photonSeconds) {
  int64_t first = 0, last = 0;
  for (const LeaseLogEntry& lease : leases) {
    if (lease.phase != 0 || lease.sentMs <= 0) continue;
    first = first == 0 ? lease.sentMs : std::min(first, lease.sentMs);
    last = std::max(last, lease.resultMs);
  }
  if (first == 0 || last <= first) return 0;
  return std::max(0.0, photonSeconds - double(last - first) * 1e-3);
}

// The coordinator holds its jobs.db exclusively: the model reads a copy of
// it (and its WAL), never the live file.
MeasuredJob readJob(const std::string& argument) {
  std::string path = argument;
  uint64_t jobId = 0;
  if (const size_t colon = argument.rfind(':'); colon != std::string::npos && colon + 1 < argument.size() &&
                                                argument.find_first_not_of("0123456789", colon + 1) == std::string::npos) {
    path = argument.substr(0, colon);
    jobId = std::stoull(argument.substr(colon + 1));
  }
  if (!fs::is_regular_file(path)) throw std::invalid_argument(fmt::format("{}: no such jobs.db", path));
  TemporaryDirectory copy("portico-cluster-model");
  for (const std::string suffix : {"", "-wal"})
    if (fs::exists(path + suffix)) fs::copy_file(path + suffix, copy.path() / ("jobs.db" + suffix));
  JobStore store((copy.path() / "jobs.db").string());
  std::optional<JobRecord> job;
  if (jobId) job = store.job(jobId);
  else
    for (const JobRecord& j : store.jobs(false))
      if (j.state == JobState::Done) job = j;
  if (!job || job->state != JobState::Done)
    throw std::invalid_argument(fmt::format("{}: {} is not a finished job", path,
                                            jobId ? fmt::format("job {}", jobId) : std::string("the newest job")));
  net::PackedReader reader(job->spec.data(), job->spec.size());
  const auto spec = reader.root<wire::JobSpec>();
  MeasuredJob measured;
  measured.name = fmt::format("{}:{}", path, job->id);
  const SceneStore scene = SceneStore::open(spec.getStore().cStr());
  measured.record.cells = scene.cells();
  const auto [photonStructure, renderStructure] = structuresOf(jobSettingsFromWire(spec));
  measured.cachedBytesPerFileByte[0] = cachedBytesPerFileByte(scene, photonStructure);
  measured.cachedBytesPerFileByte[1] = cachedBytesPerFileByte(scene, renderStructure);
  measured.record.leases = store.leaseLog(job->id);
  if (measured.record.leases.empty())
    throw std::invalid_argument(fmt::format("{}: job {} has no lease log (run by an older coordinator)", path, job->id));
  const auto counters = store.counters(job->id);
  const auto counter = [&](std::string_view name) {
    const auto it = counters.find(std::string(name));
    return it == counters.end() ? int64_t(0) : it->second;
  };
  const int64_t cpuMicros = counter(kCoordinatorCpuAtLastResultCounter) - counter(kCoordinatorCpuAtSubmitCounter);
  measured.record.coordinatorSecondsPerLease = std::max<int64_t>(0, cpuMicros) * 1e-6 / double(measured.record.leases.size());
  std::set<std::string> names;
  for (const LeaseLogEntry& lease : measured.record.leases) names.insert(lease.worker);
  measured.workers = names.size();
  const std::string budgetPrefix(kWorkerMemoryBudgetPrefix);
  for (auto it = counters.lower_bound(budgetPrefix); it != counters.end() && it->first.rfind(budgetPrefix, 0) == 0; ++it)
    measured.workerMemoryBytes = std::max<uint64_t>(measured.workerMemoryBytes, uint64_t(it->second));
  measured.photonSeconds = double(counter("time.photons_ms")) * 1e-3;
  measured.renderSeconds = double(counter("time.render_ms")) * 1e-3;
  measured.record.phaseChangeSeconds = phaseChangeSeconds(measured.record.leases);
  measured.record.phaseStartSeconds = phaseStartSeconds(measured.record.leases, measured.photonSeconds);
  double cpu = 0;
  for (const LeaseLogEntry& lease : measured.record.leases) cpu += double(std::max<int64_t>(0, lease.cpuMicros)) * 1e-6;
  const double seconds = measured.photonSeconds + measured.renderSeconds;
  if (cpu > 0 && seconds > 0)
    measured.coresHad = (cpu + measured.record.coordinatorSecondsPerLease * double(measured.record.leases.size())) / seconds;
  return measured;
}

// Where the workers' time in their leases went: what the model takes as a
// lease's own cost (CPU and blocked) and what waiting for a core added.
std::string workerTimeSummary(const std::vector<LeaseLogEntry>& leases) {
  double wall = 0, cpu = 0, waited = 0;
  bool recorded = false;
  for (const LeaseLogEntry& lease : leases) {
    wall += double(lease.leaseMicros) * 1e-6;
    if (lease.cpuMicros < 0) continue;
    recorded = true;
    cpu += double(lease.cpuMicros) * 1e-6;
    waited += double(std::max<int64_t>(0, lease.runQueueMicros)) * 1e-6;
  }
  if (!recorded) return fmt::format("workers {:.1f} s in leases (CPU not recorded)", wall);
  return fmt::format("workers {:.1f} s in leases: {:.1f} s CPU, {:.1f} s waiting for a core, {:.1f} s blocked", wall,
                     cpu, waited, std::max(0.0, wall - cpu - waited));
}

std::vector<size_t> workerCounts(const std::string& list) {
  std::vector<size_t> counts;
  size_t start = 0;
  while (start <= list.size()) {
    const size_t end = std::min(list.find(',', start), list.size());
    const std::string item = list.substr(start, end - start);
    if (item.empty() || item.find_first_not_of("0123456789") != std::string::npos || std::stoul(item) == 0 ||
        std::stoul(item) > 100000)
      throw std::invalid_argument(fmt::format("--workers: '{}' is not a worker count (1 to 100000)", item));
    counts.push_back(std::stoul(item));
    start = end + 1;
  }
  return counts;
}

// --host-cores: a count, or "measured" (-1 here).
double hostCoresOf(const std::string& value) {
  if (value == "measured") return -1;
  size_t used = 0;
  double cores = -1;
  try {
    cores = std::stod(value, &used);
  } catch (const std::exception&) {
  }
  if (used != value.size() || !(cores >= 0 && cores <= 4096))
    throw std::invalid_argument(fmt::format("--host-cores: '{}' is not a core count (0 to 4096) or 'measured'", value));
  return cores;
}

// `environment`: the run whose cores --host-cores measured takes; `costs`:
// `bench coordinator`'s figures (or null).
ClusterModelOptions modelOf(const MeasuredJob& job, size_t workers, const BenchClusterOptions& options,
                            const MeasuredJob& environment, const CoordinatorCostTable* costs) {
  ClusterModelOptions model;
  model.workers = workers;
  model.workerMemoryBytes = job.workerMemoryBytes ? job.workerMemoryBytes : parseByteSize(options.memory);
  model.latencySeconds = options.latencyMicros * 1e-6;
  const double cores = hostCoresOf(options.hostCores);
  if (cores < 0 && environment.coresHad <= 0)
    throw std::invalid_argument(fmt::format("--host-cores measured: {} has no CPU in its lease log (schema 8)",
                                            environment.name));
  model.hostCores = cores < 0 ? environment.coresHad : cores;
  model.workScale = options.workScale;
  model.leaseScale = options.leaseScale;
  if (costs) {
    const CoordinatorCost cost = costs->at(workers);
    model.coordinatorSecondsPerLease = cost.cpuSecondsPerLease;
    model.bytesPerWork[0] = cost.bytesPerWork[0];
    model.bytesPerWork[1] = cost.bytesPerWork[1];
  }
  if (options.coordinatorMsPerLease >= 0) model.coordinatorSecondsPerLease = options.coordinatorMsPerLease * 1e-3;
  if (options.bytesPerRay > 0) model.bytesPerWork[0] = model.bytesPerWork[1] = options.bytesPerRay;
  model.linkBytesPerSecond = options.linkGbit * 1e9 / 8;
  model.cachedBytesPerFileByte[0] = job.cachedBytesPerFileByte[0];
  model.cachedBytesPerFileByte[1] = job.cachedBytesPerFileByte[1];
  return model;
}

ClusterPrediction predict(const MeasuredJob& job, size_t workers, const BenchClusterOptions& options,
                          const MeasuredJob& environment, const CoordinatorCostTable* costs) {
  return simulateCluster(job.record, modelOf(job, workers, options, environment, costs));
}

double percent(double predicted, double measured) { return measured > 0 ? 100.0 * (predicted - measured) / measured : 0; }
}  // namespace

int runBenchCluster(const BenchClusterOptions& options) {
  if (options.records.empty()) throw std::invalid_argument("bench cluster: name at least one JOBS_DB[:JOB]");
  const std::vector<size_t> counts = workerCounts(options.workers);
  // Scaled work is another job: nothing measured to compare with.
  const bool scaled = options.workScale != 1;
  const double cores = hostCoresOf(options.hostCores);
  std::vector<MeasuredJob> jobs;
  for (const std::string& argument : options.records) jobs.push_back(readJob(argument));
  std::optional<CoordinatorCostTable> costTable;
  if (!options.coordinatorBench.empty()) costTable.emplace(options.coordinatorBench);
  const CoordinatorCostTable* costs = costTable ? &*costTable : nullptr;
  std::ofstream csv;
  if (!options.csv.empty()) {
    csv.open(options.csv);
    if (!csv) throw std::runtime_error(fmt::format("{}: cannot be written", options.csv));
    csv << "record,workers,measured_s,predicted_s,photons_s,render_s,leases,loads,coordinator_utilization,"
           "worker_utilization,choose_cell_us,measured_photons_s,measured_render_s,choose_cell_calls\n";
  }
  // A prediction and, for a measured run (`measured`), its error in all and
  // in each phase.
  const auto row = [&](const MeasuredJob& job, size_t workers, const MeasuredJob* measured,
                       const ClusterPrediction& p) {
    if (scaled) measured = nullptr;
    const auto phase = [&](double predicted, double seconds) {
      return measured && seconds > 0 ? fmt::format("{:.1f} {:+.0f}%", predicted, percent(predicted, seconds))
                                     : fmt::format("{:.1f}", predicted);
    };
    const double total = measured ? measured->photonSeconds + measured->renderSeconds : 0;
    std::cout << fmt::format("{:>7} {:>10} {:>10} {:>7} {:>13} {:>13} {:>8} {:>11} {:>6.0f}% {:>6.0f}% {:>8.1f}\n",
                             workers, total > 0 ? fmt::format("{:.1f}", total) : "-",
                             fmt::format("{:.1f}", p.seconds()),
                             total > 0 ? fmt::format("{:+.0f}%", percent(p.seconds(), total)) : "-",
                             phase(p.phases[0].seconds, measured ? measured->photonSeconds : 0),
                             phase(p.phases[1].seconds, measured ? measured->renderSeconds : 0),
                             p.phases[0].leases + p.phases[1].leases,
                             fmt::format("{} + {}", p.phases[0].loads, p.phases[1].loads),
                             100 * p.coordinatorUtilization(), 100 * p.workerUtilization(workers), p.chooseCellMicros);
    const auto optional = [](double seconds) { return seconds > 0 ? fmt::format("{:.3f}", seconds) : std::string(); };
    if (csv.is_open())
      csv << fmt::format("{},{},{},{:.3f},{:.3f},{:.3f},{},{},{:.4f},{:.4f},{:.2f},{},{},{}\n", job.name, workers,
                         optional(total), p.seconds(), p.phases[0].seconds, p.phases[1].seconds,
                         p.phases[0].leases + p.phases[1].leases, p.phases[0].loads + p.phases[1].loads,
                         p.coordinatorUtilization(), p.workerUtilization(workers), p.chooseCellMicros,
                         optional(measured ? measured->photonSeconds : 0),
                         optional(measured ? measured->renderSeconds : 0), p.chooseCellCalls);
  };
  const std::string header = fmt::format("{:>7} {:>10} {:>10} {:>7} {:>13} {:>13} {:>8} {:>11} {:>7} {:>7} {:>8}\n",
                                         "workers", "measured", "predicted", "error", "photons", "render", "leases",
                                         "loads", "coord", "work", "choose");
  for (const MeasuredJob& job : jobs) {
    const bool named = std::any_of(job.record.leases.begin(), job.record.leases.end(),
                                   [](const LeaseLogEntry& lease) { return lease.moreCellsLogged; });
    std::cout << fmt::format("{}: {} leases by {} workers, coordinator {:.2f} ms CPU per lease; {}; the job had "
                             "{:.2f} cores; a cached cell takes {:.2f} (photons) and {:.2f} (render) bytes per file "
                             "byte; {}\n",
                             job.name, job.record.leases.size(), job.workers,
                             job.record.coordinatorSecondsPerLease * 1e3, workerTimeSummary(job.record.leases),
                             job.coresHad, job.cachedBytesPerFileByte[0], job.cachedBytesPerFileByte[1],
                             named ? "each worker's cache simulated"
                                   : "its loads replayed as recorded (its leases' more cells are not named)")
              << header;
    row(job, job.workers, &job, predict(job, job.workers, options, job, costs));
    // The other measured runs, predicted from this one's record.
    for (const MeasuredJob& other : jobs)
      if (&other != &job && other.workers != job.workers)
        row(job, other.workers, &other, predict(job, other.workers, options, other, costs));
  }
  if (costs || options.coordinatorMsPerLease >= 0 || options.bytesPerRay > 0) {
    std::cout << "the coordinator charged, per lease:";
    for (size_t workers : counts) {
      const ClusterModelOptions m = modelOf(jobs.front(), workers, options, jobs.front(), costs);
      std::cout << fmt::format(" {} workers {:.3f} ms CPU{};", workers, m.coordinatorSecondsPerLease * 1e3,
                               m.bytesPerWork[0] > 0 || m.bytesPerWork[1] > 0
                                   ? fmt::format(" + {:.1f} / {:.1f} bytes per ray (photons / render)",
                                                 m.bytesPerWork[0], m.bytesPerWork[1])
                                   : "");
    }
    std::cout << fmt::format(" bytes on a {} Gbit/s link\n", options.linkGbit);
  }
  std::cout << fmt::format("predicted from {}{}{}:\n", jobs.front().name,
                           cores != 0 ? fmt::format(", all on {:.2f} cores", cores < 0 ? jobs.front().coresHad : cores)
                                      : std::string(", a machine per worker"),
                           scaled ? fmt::format(", its photon pass's tracing work x{}", options.workScale) : std::string())
            << header;
  for (size_t workers : counts)
    row(jobs.front(), workers, nullptr, predict(jobs.front(), workers, options, jobs.front(), costs));
  return 0;
}

}  // namespace portico::cli
