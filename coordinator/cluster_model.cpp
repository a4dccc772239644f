#include "coordinator/cluster_model.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <limits>
#include <map>
#include <optional>
#include <queue>
#include <set>
#include <string>
#include <tuple>

#include "coordinator/cell_choice.h"
#include "coordinator/shared_cores.h"
#include "coordinator/worker_registry.h"

namespace portico {

namespace {
constexpr uint64_t kModelJob = 1;

// A lease's own time on its worker (its wall time less its wait for a core)
// and the CPU share of it; a row without CPU recorded (schema 8) counts its
// wall time, all of it CPU.
struct OwnTime {
  double seconds = 0, cpuSeconds = 0;
};
OwnTime ownTime(const LeaseLogEntry& lease) {
  const double wall = double(lease.leaseMicros) * 1e-6;
  if (lease.cpuMicros < 0) return {wall, wall};
  const double own = std::max(0.0, wall - double(std::max<int64_t>(0, lease.runQueueMicros)) * 1e-6);
  return {own, std::min(own, double(lease.cpuMicros) * 1e-6)};
}

// A piece of a cell's queue: one recorded lease's work (times the work
// scale) and the own seconds of the loads it made, which recur with it.
struct Piece {
  int64_t work = 0;
  double loadSeconds = 0;
};

// What a phase's leases measured, per cell: the work queued for it and its
// tracing's own seconds per unit of work and CPU share; and the phase's
// load seconds per triangle and CPU share of all its time.
struct PhaseCosts {
  std::map<uint32_t, std::deque<Piece>> pieces;
  std::map<uint32_t, double> secondsPerWork, cpuShare;
  double loadSecondsPerTriangle = 0, phaseCpuShare = 1;
};

PhaseCosts phaseCosts(const ClusterRecord& record, int phase, double workScale) {
  PhaseCosts costs;
  struct Traced {
    double seconds = 0, cpuSeconds = 0;
    int64_t work = 0;
  };
  std::map<uint32_t, Traced> traced;
  double loadSeconds = 0, triangles = 0, own = 0, cpu = 0;
  for (const LeaseLogEntry& lease : record.leases) {
    if (lease.phase != phase || lease.work <= 0) continue;
    const OwnTime time = ownTime(lease);
    const double wall = double(lease.leaseMicros) * 1e-6;
    // Its loads' own time: their wall time as the lease's is its own.
    const double load = std::min(time.seconds, wall > 0 ? double(lease.loadMicros) * 1e-6 * time.seconds / wall : 0.0);
    // A lease of several cells counts as its own cell's: the log keeps its
    // work and time together.
    const int64_t work = std::max<int64_t>(1, std::llround(double(lease.work) * workScale));
    costs.pieces[lease.cell].push_back({work, load});
    Traced& t = traced[lease.cell];
    t.seconds += time.seconds - load;
    t.cpuSeconds += time.cpuSeconds;
    t.work += lease.work;
    t.seconds = std::max(0.0, t.seconds);
    loadSeconds += load;
    triangles += double(lease.trianglesLoaded);
    own += time.seconds;
    cpu += time.cpuSeconds;
  }
  for (const auto& [cell, t] : traced) {
    costs.secondsPerWork[cell] = t.seconds / double(std::max<int64_t>(1, t.work));
    costs.cpuShare[cell] = t.seconds > 0 ? std::min(1.0, t.cpuSeconds / (t.seconds + 1e-12)) : 1.0;
  }
  costs.loadSecondsPerTriangle = triangles > 0 ? loadSeconds / triangles : 0;
  costs.phaseCpuShare = own > 0 ? cpu / own : 1;
  return costs;
}

// The queue of one phase as JobStore keeps it: unleased pieces per cell,
// ranked by pending work (most first, ties: lower cell).
class ModelQueue {
 public:
  ModelQueue(std::map<uint32_t, std::deque<Piece>> pieces, int phase) : pieces_(std::move(pieces)), phase_(phase) {
    for (const auto& [cell, queue] : pieces_) {
      int64_t work = 0;
      for (const Piece& piece : queue) work += piece.work;
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
  // The oldest pieces up to maxWork, at least some (JobStore::openLease
  // takes whole batches; a piece larger than maxWork, a recorded lease
  // scaled up, is cut as the coordinator's finer batches would be). The
  // loads of a piece go with its first part.
  Piece take(uint32_t cell, int64_t maxWork) {
    auto& queue = pieces_[cell];
    Piece taken;
    while (!queue.empty() && (taken.work == 0 || taken.work + queue.front().work <= maxWork)) {
      Piece& front = queue.front();
      const int64_t part = taken.work == 0 ? std::min(front.work, std::max<int64_t>(1, maxWork)) : front.work;
      taken.work += part;
      taken.loadSeconds += front.loadSeconds;
      front.loadSeconds = 0;
      front.work -= part;
      if (front.work > 0) break;
      queue.pop_front();
    }
    ranked_.erase({-pending_[cell], cell});
    pending_[cell] -= taken.work;
    if (!queue.empty()) ranked_.insert({-pending_[cell], cell});
    return taken;
  }

 private:
  std::map<uint32_t, std::deque<Piece>> pieces_;
  std::map<uint32_t, int64_t> pending_;
  std::set<std::pair<int64_t, uint32_t>> ranked_;
  int phase_;
};

// A lease as the model runs it: its own time on a worker (CPU, then the
// rest blocked) and its loads.
struct ModelLease {
  uint64_t id = 0;
  size_t worker = 0;
  double cpuSeconds = 0, blockedSeconds = 0, loadSeconds = 0;
  int64_t triangles = 0;
  double startedAt = 0, wallSeconds = 0;
};

// A worker of the model: the coordinator's view of it lives in the
// registry (WorkerInfo); here what it really holds, the leases it has
// received, and the one it traces.
struct ModelWorker {
  std::string identity;
  CellCacheModel cache;
  std::deque<ModelLease> received;
  std::optional<ModelLease> tracing;
};

// The coordinator's work, one task at a time: a Result to apply, or a
// lease to send.
struct CoordinatorTask {
  bool apply = false;
  ModelLease lease;
  double cpuSeconds = 0;
};

// What happens at a set time: a lease reaches its worker, a Result the
// coordinator, a lease's blocked time ends.
struct TimedEvent {
  enum Kind { LeaseArrives, ResultArrives, BlockedEnds } kind = LeaseArrives;
  double at = 0;
  uint64_t order = 0;
  ModelLease lease;
  bool operator>(const TimedEvent& o) const { return std::tie(at, order) > std::tie(o.at, o.order); }
};

int64_t toMs(double seconds) { return std::llround(seconds * 1000.0); }

// Thread ids on the shared cores: the coordinator, then the workers.
constexpr size_t kCoordinatorThread = 0;

class PhaseSimulation {
 public:
  PhaseSimulation(const ClusterRecord& record, const ClusterModelOptions& options, int phase,
                  WorkerRegistry& registry, std::vector<ModelWorker>& workers, double startAt)
      : record_(record), options_(options), phase_(phase), costs_(phaseCosts(record, phase, options.workScale)),
        queue_(costs_.pieces, phase), registry_(registry), workers_(workers), cores_(options.hostCores),
        now_(startAt) {}

  PhasePrediction run(uint64_t& nextLease, double& chooseSeconds, int64_t& chooseCalls) {
    nextLease_ = &nextLease;
    const double start = now_;
    dispatch();
    for (;;) {
      startIdleThreads();
      const double next = std::min(cores_.nextEnd(now_), events_.empty() ? cores_.nextEnd(now_) : events_.top().at);
      if (!std::isfinite(next)) break;
      const std::vector<size_t> ended = cores_.advance(now_, next);
      now_ = next;
      for (size_t thread : ended) burstEnded(thread);
      while (!events_.empty() && events_.top().at <= now_) {
        const TimedEvent event = events_.top();
        events_.pop();
        handle(event);
      }
    }
    prediction_.seconds = now_ - start;
    chooseSeconds += chooseSeconds_;
    chooseCalls += chooseCalls_;
    return prediction_;
  }
  double endAt() const { return now_; }

 private:
  double perLease() const { return record_.coordinatorSecondsPerLease; }

  void schedule(TimedEvent::Kind kind, double at, const ModelLease& lease) {
    events_.push({kind, at, nextOrder_++, lease});
  }

  // Idle threads with work start it: the coordinator its next task, each
  // worker its next received lease.
  void startIdleThreads() {
    if (!coordinatorBusy_ && !tasks_.empty()) {
      coordinatorBusy_ = true;
      cores_.start(kCoordinatorThread, tasks_.front().cpuSeconds);
    }
    while (!idleWorkers_.empty()) {
      ModelWorker& worker = workers_[idleWorkers_.front()];
      idleWorkers_.pop_front();
      if (worker.tracing || worker.received.empty()) continue;
      worker.tracing = worker.received.front();
      worker.received.pop_front();
      worker.tracing->startedAt = now_;
      cores_.start(kCoordinatorThread + 1 + worker.tracing->worker, worker.tracing->cpuSeconds);
    }
  }

  void burstEnded(size_t thread) {
    if (thread == kCoordinatorThread) {
      const CoordinatorTask task = tasks_.front();
      tasks_.pop_front();
      coordinatorBusy_ = false;
      if (task.apply) applyResult(task.lease);
      else schedule(TimedEvent::LeaseArrives, now_ + options_.latencySeconds, task.lease);
      return;
    }
    ModelWorker& worker = workers_[thread - 1];
    if (worker.tracing->blockedSeconds > 0) schedule(TimedEvent::BlockedEnds, now_ + worker.tracing->blockedSeconds, *worker.tracing);
    else finishLease(worker);
  }

  void handle(const TimedEvent& event) {
    switch (event.kind) {
      case TimedEvent::LeaseArrives:
        workers_[event.lease.worker].received.push_back(event.lease);
        idleWorkers_.push_back(event.lease.worker);
        break;
      case TimedEvent::BlockedEnds: finishLease(workers_[event.lease.worker]); break;
      case TimedEvent::ResultArrives:
        tasks_.push_back({true, event.lease, perLease() / 2});
        prediction_.coordinatorBusySeconds += perLease() / 2;
        break;
    }
  }

  void finishLease(ModelWorker& worker) {
    ModelLease lease = *worker.tracing;
    worker.tracing.reset();
    lease.wallSeconds = now_ - lease.startedAt;
    schedule(TimedEvent::ResultArrives, now_ + options_.latencySeconds, lease);
    idleWorkers_.push_back(lease.worker);
  }

  // The Result applied: the coordinator learns the worker's speed (its
  // lease's wall time, as a worker reports it) and load cost, and leases
  // again.
  void applyResult(const ModelLease& lease) {
    WorkerInfo& info = registry_.at(workers_[lease.worker].identity);
    info.recordLease(lease.id, toMs(now_), std::llround(lease.wallSeconds * 1e6));
    info.recordLoads(lease.triangles, std::llround(lease.loadSeconds * 1e6));
    info.leases.erase(lease.id);
    dispatch();
  }

  void dispatch() {
    for (size_t w = 0; w < workers_.size(); ++w) {
      WorkerInfo& info = registry_.at(workers_[w].identity);
      for (size_t k = 0; k < WorkerInfo::kMostLeasesInFlight && info.wantsLease(); ++k) {
        if (queue_.empty()) return;
        if (!assign(w, info)) break;
      }
    }
  }

  // One lease, chosen as Coordinator::assignWork chooses it; sent once the
  // coordinator has spent its CPU on it.
  bool assign(size_t w, WorkerInfo& info) {
    const auto candidates = queue_.candidates(kLeaseCandidates);
    const auto started = std::chrono::steady_clock::now();
    const PendingCell* chosen = chooseCell(candidates, record_.cells, info, registry_);
    const double chooseSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    chooseSeconds_ += chooseSeconds;
    ++chooseCalls_;
    if (!chosen) return false;
    const Piece first = queue_.take(chosen->cell, info.nextLeaseWork(kMaxLeaseWork));
    std::vector<std::pair<uint32_t, Piece>> cells{{chosen->cell, first}};
    const int64_t leaseWork = addMoreCells(
        candidates, *chosen, record_.cells, info, registry_, first.work, [](const PendingCell&) { return false; },
        [&](const PendingCell& c, int64_t maxWork) {
          const Piece taken = queue_.take(c.cell, maxWork);
          cells.emplace_back(c.cell, taken);
          return taken.work;
        });
    const double cost = perLease() / 2 + chooseSeconds;
    prediction_.coordinatorBusySeconds += cost;
    const uint64_t lease = (*nextLease_)++;
    info.leases.emplace(lease, WorkerInfo::LeaseInFlight{toMs(now_), leaseWork, uint32_t(cells.size() - 1)});
    for (const auto& [cell, piece] : cells) info.cells.use(kModelJob, cell, cachedBytesOf(record_.cells, cell));
    tasks_.push_back({false, leaseOf(w, lease, cells), cost});
    ++prediction_.leases;
    return true;
  }

  // What the lease will take its worker: a load for each cell its cache
  // lacks that another worker loaded in this phase (a second copy; a
  // cell's first loads are the record's, in its pieces), then the cells'
  // work, CPU first and then the time the record spent blocked. Worked out
  // as it is leased: a worker traces its leases in that order.
  ModelLease leaseOf(size_t w, uint64_t id, const std::vector<std::pair<uint32_t, Piece>>& cells) {
    ModelWorker& worker = workers_[w];
    ModelLease lease{id, w};
    // The worker's cache keys a cell by its structure too: the render
    // phase's (bvh) is not the photon pass's (grid).
    const uint64_t cacheKey = uint64_t(phase_) + 1;
    double traceSeconds = 0, traceCpu = 0;
    for (const auto& [cell, piece] : cells) {
      const bool loadedElsewhere = !loadedBy_[cell].empty() && !loadedBy_[cell].count(w);
      if (!worker.cache.holds(cacheKey, cell)) {
        loadedBy_[cell].insert(w);
        if (loadedElsewhere) {
          const int64_t triangles = cell < record_.cells.size() ? int64_t(record_.cells[cell].triangleCount) : 0;
          lease.loadSeconds += double(triangles) * costs_.loadSecondsPerTriangle;
          lease.triangles += triangles;
          ++prediction_.loads;
        }
      }
      lease.loadSeconds += piece.loadSeconds;
      const uint64_t fileBytes = cell < record_.cells.size() ? record_.cells[cell].byteCount : 0;
      worker.cache.use(cacheKey, cell, uint64_t(options_.cachedBytesPerFileByte * double(fileBytes)));
      const auto rate = costs_.secondsPerWork.find(cell);
      const double seconds = double(piece.work) * (rate != costs_.secondsPerWork.end() ? rate->second : meanSecondsPerWork());
      const auto share = costs_.cpuShare.find(cell);
      traceSeconds += seconds;
      traceCpu += seconds * (share != costs_.cpuShare.end() ? share->second : costs_.phaseCpuShare);
    }
    lease.cpuSeconds = traceCpu + lease.loadSeconds * costs_.phaseCpuShare;
    lease.blockedSeconds = std::max(0.0, traceSeconds + lease.loadSeconds - lease.cpuSeconds);
    prediction_.workerBusySeconds += traceSeconds + lease.loadSeconds;
    return lease;
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
  SharedCores cores_;
  std::deque<CoordinatorTask> tasks_;
  bool coordinatorBusy_ = false;
  std::deque<size_t> idleWorkers_;   // workers that may start a received lease
  std::priority_queue<TimedEvent, std::vector<TimedEvent>, std::greater<TimedEvent>> events_;
  uint64_t nextOrder_ = 0;
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
    // The coordinator alone between the phases, as the record measured.
    const double change = phase == 1 ? record.phaseChangeSeconds : 0;
    PhaseSimulation simulation(record, options, phase, registry, workers, at + change);
    prediction.phases[phase] = simulation.run(nextLease, chooseSeconds, chooseCalls);
    prediction.phases[phase].seconds += change;
    prediction.phases[phase].coordinatorBusySeconds += change;
    at += prediction.phases[phase].seconds;
  }
  prediction.chooseCellMicros = chooseCalls ? chooseSeconds * 1e6 / double(chooseCalls) : 0;
  return prediction;
}

}  // namespace portico
