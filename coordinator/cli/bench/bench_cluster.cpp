#include "coordinator/cli/bench/bench_cluster.h"

#include <fmt/format.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>
#include <stdexcept>

#include "common/net/message.h"
#include "common/scene/store/scene_store.h"
#include "common/util/size_parse.h"
#include "common/util/temporary_directory.h"
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
};

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
  measured.record.cells = SceneStore::open(spec.getStore().cStr()).cells();
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

// `environment`: the run whose cores --host-cores measured takes.
ClusterModelOptions modelOf(const MeasuredJob& job, size_t workers, const BenchClusterOptions& options,
                            const MeasuredJob& environment) {
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
  return model;
}

ClusterPrediction predict(const MeasuredJob& job, size_t workers, const BenchClusterOptions& options,
                          const MeasuredJob& environment) {
  return simulateCluster(job.record, modelOf(job, workers, options, environment));
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
  std::ofstream csv;
  if (!options.csv.empty()) {
    csv.open(options.csv);
    if (!csv) throw std::runtime_error(fmt::format("{}: cannot be written", options.csv));
    csv << "record,workers,measured_s,predicted_s,photons_s,render_s,leases,loads,coordinator_utilization,"
           "worker_utilization,choose_cell_us\n";
  }
  const auto row = [&](const MeasuredJob& job, size_t workers, double measured, const ClusterPrediction& p) {
    if (scaled) measured = 0;
    std::cout << fmt::format("{:>7} {:>10} {:>10} {:>7} {:>9.1f} {:>9.1f} {:>8} {:>7} {:>6.0f}% {:>6.0f}% {:>8.1f}\n",
                             workers, measured > 0 ? fmt::format("{:.1f}", measured) : "-",
                             fmt::format("{:.1f}", p.seconds()),
                             measured > 0 ? fmt::format("{:+.0f}%", percent(p.seconds(), measured)) : "-",
                             p.phases[0].seconds, p.phases[1].seconds, p.phases[0].leases + p.phases[1].leases,
                             p.phases[0].loads + p.phases[1].loads, 100 * p.coordinatorUtilization(),
                             100 * p.workerUtilization(workers), p.chooseCellMicros);
    if (csv.is_open())
      csv << fmt::format("{},{},{},{:.3f},{:.3f},{:.3f},{},{},{:.4f},{:.4f},{:.2f}\n", job.name, workers,
                         measured > 0 ? fmt::format("{:.3f}", measured) : "", p.seconds(), p.phases[0].seconds,
                         p.phases[1].seconds, p.phases[0].leases + p.phases[1].leases,
                         p.phases[0].loads + p.phases[1].loads, p.coordinatorUtilization(),
                         p.workerUtilization(workers), p.chooseCellMicros);
  };
  const std::string header = fmt::format("{:>7} {:>10} {:>10} {:>7} {:>9} {:>9} {:>8} {:>7} {:>7} {:>7} {:>8}\n",
                                         "workers", "measured", "predicted", "error", "photons", "render", "leases",
                                         "loads", "coord", "work", "choose");
  for (const MeasuredJob& job : jobs) {
    std::cout << fmt::format("{}: {} leases by {} workers, coordinator {:.2f} ms CPU per lease; {}; the job had "
                             "{:.2f} cores\n",
                             job.name, job.record.leases.size(), job.workers,
                             job.record.coordinatorSecondsPerLease * 1e3, workerTimeSummary(job.record.leases),
                             job.coresHad)
              << header;
    row(job, job.workers, job.photonSeconds + job.renderSeconds, predict(job, job.workers, options, job));
    // The other measured runs, predicted from this one's record.
    for (const MeasuredJob& other : jobs)
      if (&other != &job && other.workers != job.workers)
        row(job, other.workers, other.photonSeconds + other.renderSeconds, predict(job, other.workers, options, other));
  }
  std::cout << fmt::format("predicted from {}{}{}:\n", jobs.front().name,
                           cores != 0 ? fmt::format(", all on {:.2f} cores", cores < 0 ? jobs.front().coresHad : cores)
                                      : std::string(", a machine per worker"),
                           scaled ? fmt::format(", its tracing work x{}", options.workScale) : std::string())
            << header;
  for (size_t workers : counts) row(jobs.front(), workers, 0, predict(jobs.front(), workers, options, jobs.front()));
  return 0;
}

}  // namespace portico::cli
