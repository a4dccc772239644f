#include "coordinator/cluster_model.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <limits>
#include <map>
#include <queue>
#include <set>
#include <string>

#include "coordinator/cell_choice.h"
#include "coordinator/worker_registry.h"

namespace portico {

namespace {
constexpr uint64_t kModelJob = 1;

// What a phase's leases measured, per cell: the work queued for it (as the
// batches the recorded leases took) and its trace seconds per unit of work;
// and the phase's load seconds per triangle.
struct PhaseCosts {
  std::map<uint32_t, std::deque<int64_t>> batches;
  std::map<uint32_t, double> secondsPerWork;
  double loadSecondsPerTriangle = 0;
};

PhaseCosts phaseCosts(const ClusterRecord& record, int phase) {
  PhaseCosts costs;
  std::map<uint32_t, std::pair<double, int64_t>> traced;   // seconds, work
  double loadSeconds = 0, triangles = 0;
  for (const LeaseLogEntry& lease : record.leases) {
    if (lease.phase != phase || lease.work <= 0) continue;
    // A lease of several cells counts as its own cell's: the log keeps its
    // work and time together.
    costs.batches[lease.cell].push_back(lease.work);
    auto& [seconds, work] = traced[lease.cell];
    // Loads included: the record's own loads (first loads and the
    // reloads its workers' caches made) recur at any worker count.
    seconds += double(lease.leaseMicros) * 1e-6;
    work += lease.work;
    loadSeconds += lease.loadMicros * 1e-6;
    triangles += double(lease.trianglesLoaded);
  }
  for (const auto& [cell, t] : traced) costs.secondsPerWork[cell] = t.first / double(std::max<int64_t>(1, t.second));
  costs.loadSecondsPerTriangle = triangles > 0 ? loadSeconds / triangles : 0;
  return costs;
}

// The queue of one phase as JobStore keeps it: unleased batches per cell,
// ranked by pending work (most first, ties: lower cell).
class ModelQueue {
 public:
  ModelQueue(std::map<uint32_t, std::deque<int64_t>> batches, int phase) : batches_(std::move(batches)), phase_(phase) {
    for (const auto& [cell, queue] : batches_) {
      int64_t work = 0;
      for (int64_t w : queue) work += w;
      pending_[cell] = work;
      ranked_.insert({-work, cell});
    }
  }
  bool empty() const { return ranked_.empty(); }
  std::vector<PendingCell> candidates(size_t limit) const {
    std::vector<PendingCell> result;
    for (auto it = ranked_.begin(); it != ranked_.end() && result.size() < limit; ++it)
      result.push_back({kModelJob, it->second, phase_, -it->first});
    return result;
  }
  // The oldest batches up to maxWork, at least one (JobStore::openLease).
  int64_t take(uint32_t cell, int64_t maxWork) {
    auto& queue = batches_[cell];
    int64_t taken = 0;
    while (!queue.empty() && (taken == 0 || taken + queue.front() <= maxWork)) {
      taken += queue.front();
      queue.pop_front();
    }
    ranked_.erase({-pending_[cell], cell});
    pending_[cell] -= taken;
    if (!queue.empty()) ranked_.insert({-pending_[cell], cell});
    return taken;
  }

 private:
  std::map<uint32_t, std::deque<int64_t>> batches_;
  std::map<uint32_t, int64_t> pending_;
  std::set<std::pair<int64_t, uint32_t>> ranked_;
  int phase_;
};

// A worker of the model: the coordinator's view of it lives in the
// registry (WorkerInfo); here what it really holds and when its tracing
// thread is free.
struct ModelWorker {
  std::string identity;
  CellCacheModel cache;
  double traceFreeAt = 0;
};

struct ResultEvent {
  double at = 0;
  size_t worker = 0;
  uint64_t lease = 0;
  double workerSeconds = 0, loadSeconds = 0;
  int64_t triangles = 0;
  bool operator>(const ResultEvent& o) const { return std::tie(at, lease) > std::tie(o.at, o.lease); }
};

int64_t toMs(double seconds) { return std::llround(seconds * 1000.0); }

class PhaseSimulation {
 public:
  PhaseSimulation(const ClusterRecord& record, const ClusterModelOptions& options, int phase,
                  WorkerRegistry& registry, std::vector<ModelWorker>& workers, double startAt)
      : record_(record), options_(options), phase_(phase), costs_(phaseCosts(record, phase)),
        queue_(costs_.batches, phase), registry_(registry), workers_(workers), coordinatorFreeAt_(startAt),
        now_(startAt) {}

  PhasePrediction run(uint64_t& nextLease, double& chooseSeconds, int64_t& chooseCalls) {
    nextLease_ = &nextLease;
    const double start = now_;
    dispatch();
    double end = start;
    while (!events_.empty()) {
      const ResultEvent event = events_.top();
      events_.pop();
      now_ = std::max(event.at, coordinatorFreeAt_) + perLease() / 2;   // the Result applied
      coordinatorFreeAt_ = now_;
      prediction_.coordinatorBusySeconds += perLease() / 2;
      WorkerInfo& info = registry_.at(workers_[event.worker].identity);
      info.recordLease(event.lease, toMs(now_), std::llround(event.workerSeconds * 1e6));
      info.recordLoads(event.triangles, std::llround(event.loadSeconds * 1e6));
      info.leases.erase(event.lease);
      end = now_;
      dispatch();
    }
    prediction_.seconds = end - start;
    chooseSeconds += chooseSeconds_;
    chooseCalls += chooseCalls_;
    return prediction_;
  }
  double endAt() const { return now_; }

 private:
  double perLease() const { return record_.coordinatorSecondsPerLease; }

  void dispatch() {
    for (size_t w = 0; w < workers_.size(); ++w) {
      WorkerInfo& info = registry_.at(workers_[w].identity);
      for (size_t k = 0; k < WorkerInfo::kMostLeasesInFlight && info.wantsLease(); ++k) {
        if (queue_.empty()) return;
        if (!assign(w, info)) break;
      }
    }
  }

  // One lease, chosen as Coordinator::assignWork chooses it.
  bool assign(size_t w, WorkerInfo& info) {
    const auto candidates = queue_.candidates(kLeaseCandidates);
    const auto started = std::chrono::steady_clock::now();
    const PendingCell* chosen = chooseCell(candidates, record_.cells, info, registry_);
    const double chooseSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    chooseSeconds_ += chooseSeconds;
    ++chooseCalls_;
    if (!chosen) return false;
    std::vector<std::pair<uint32_t, int64_t>> cells{{chosen->cell, queue_.take(chosen->cell, info.nextLeaseWork(kMaxLeaseWork))}};
    const int64_t leaseWork = addMoreCells(
        candidates, *chosen, record_.cells, info, registry_, cells.front().second,
        [](const PendingCell&) { return false; },
        [&](const PendingCell& c, int64_t maxWork) {
          const int64_t taken = queue_.take(c.cell, maxWork);
          cells.emplace_back(c.cell, taken);
          return taken;
        });
    const double cost = perLease() / 2 + chooseSeconds;
    coordinatorFreeAt_ = std::max(coordinatorFreeAt_, now_) + cost;
    prediction_.coordinatorBusySeconds += cost;
    const uint64_t lease = (*nextLease_)++;
    info.leases.emplace(lease, WorkerInfo::LeaseInFlight{toMs(coordinatorFreeAt_), leaseWork, uint32_t(cells.size() - 1)});
    for (const auto& [cell, work] : cells) info.cells.use(kModelJob, cell, cachedBytesOf(record_.cells, cell));
    trace(w, lease, cells, coordinatorFreeAt_ + options_.latencySeconds);
    ++prediction_.leases;
    return true;
  }

  // The worker traces the lease once it arrives and its earlier leases are
  // done: a load for each cell its cache lacks, then the cell's work.
  void trace(size_t w, uint64_t lease, const std::vector<std::pair<uint32_t, int64_t>>& cells, double arrivesAt) {
    ModelWorker& worker = workers_[w];
    ResultEvent event{0, w, lease};
    // The worker's cache keys a cell by its structure too: the render
    // phase's (bvh) is not the photon pass's (grid).
    const uint64_t cacheKey = uint64_t(phase_) + 1;
    for (const auto& [cell, work] : cells) {
      // A second copy: the cell is loaded here while another worker
      // loaded it in this phase (its first load is in the record's times).
      const bool loadedElsewhere = !loadedBy_[cell].empty() && !loadedBy_[cell].count(w);
      if (!worker.cache.holds(cacheKey, cell)) {
        loadedBy_[cell].insert(w);
        if (loadedElsewhere) {
          const int64_t triangles = cell < record_.cells.size() ? int64_t(record_.cells[cell].triangleCount) : 0;
          event.loadSeconds += double(triangles) * costs_.loadSecondsPerTriangle;
          event.triangles += triangles;
          ++prediction_.loads;
        }
      }
      const uint64_t fileBytes = cell < record_.cells.size() ? record_.cells[cell].byteCount : 0;
      worker.cache.use(cacheKey, cell, uint64_t(options_.cachedBytesPerFileByte * double(fileBytes)));
      const auto rate = costs_.secondsPerWork.find(cell);
      event.workerSeconds += double(work) * (rate != costs_.secondsPerWork.end() ? rate->second : meanSecondsPerWork());
    }
    event.workerSeconds += event.loadSeconds;
    const double start = std::max(arrivesAt, worker.traceFreeAt);
    worker.traceFreeAt = start + event.workerSeconds;
    event.at = worker.traceFreeAt + options_.latencySeconds;
    prediction_.workerBusySeconds += event.workerSeconds;
    events_.push(event);
  }

  double meanSecondsPerWork() const {
    double sum = 0;
    for (const auto& [cell, rate] : costs_.secondsPerWork) sum += rate;
    return costs_.secondsPerWork.empty() ? 0 : sum / double(costs_.secondsPerWork.size());
  }

  static constexpr int64_t kMaxLeaseWork = 50000;   // the coordinator's --lease-rays default
  const ClusterRecord& record_;
  const ClusterModelOptions& options_;
  int phase_;
  PhaseCosts costs_;
  ModelQueue queue_;
  WorkerRegistry& registry_;
  std::vector<ModelWorker>& workers_;
  std::priority_queue<ResultEvent, std::vector<ResultEvent>, std::greater<ResultEvent>> events_;
  double coordinatorFreeAt_;
  double now_;
  uint64_t* nextLease_ = nullptr;
  PhasePrediction prediction_;
  std::map<uint32_t, std::set<size_t>> loadedBy_;   // the workers that loaded each cell in this phase
  double chooseSeconds_ = 0;
  int64_t chooseCalls_ = 0;
};
}  // namespace

double ClusterPrediction::coordinatorUtilization() const {
  const double busy = phases[0].coordinatorBusySeconds + phases[1].coordinatorBusySeconds;
  return seconds() > 0 ? busy / seconds() : 0;
}

double ClusterPrediction::workerUtilization(size_t workers) const {
  const double busy = phases[0].workerBusySeconds + phases[1].workerBusySeconds;
  return seconds() > 0 && workers > 0 ? busy / (seconds() * double(workers)) : 0;
}

ClusterPrediction simulateCluster(const ClusterRecord& record, const ClusterModelOptions& options) {
  WorkerRegistry registry;
  std::vector<ModelWorker> workers(options.workers);
  for (size_t w = 0; w < options.workers; ++w) {
    workers[w].identity = "worker-" + std::to_string(w);
    workers[w].cache.setBudget(options.workerMemoryBytes);
    WorkerInfo& info = registry[workers[w].identity];
    info.identity = info.name = workers[w].identity;
    info.memoryBytes = options.workerMemoryBytes;
    info.cells.setBudget(options.workerMemoryBytes);
    info.ready = true;
  }
  ClusterPrediction prediction;
  uint64_t nextLease = 1;
  double chooseSeconds = 0, at = 0;
  int64_t chooseCalls = 0;
  for (int phase = 0; phase < 2; ++phase) {
    for (ModelWorker& worker : workers) worker.traceFreeAt = std::max(worker.traceFreeAt, at);
    PhaseSimulation simulation(record, options, phase, registry, workers, at);
    prediction.phases[phase] = simulation.run(nextLease, chooseSeconds, chooseCalls);
    at += prediction.phases[phase].seconds;
  }
  prediction.chooseCellMicros = chooseCalls ? chooseSeconds * 1e6 / double(chooseCalls) : 0;
  return prediction;
}

}  // namespace portico
