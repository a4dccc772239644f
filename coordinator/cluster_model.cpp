#include "coordinator/cluster_model.h"

#include <time.h>

#include <algorithm>
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

// A piece of a cell's queue: one recorded lease's work in it (times the
// work scale), and, from a record that does not name its leases' more
// cells, the own seconds of the loads that lease made, which recur with it.
struct Piece {
  int64_t work = 0;
  double loadSeconds = 0;
  // When it is queued, as the share of the phase's work done: a cell's
  // later pieces are rays and photons that other cells' leases send back
  // to it, queued in the record once its previous lease had come back
  // (0: from the start; always, from a record without its more cells).
  double releaseAt = 0;
};

// Whether the phase's leases name every cell they touched (schema 10): then
// each cell's work is queued in that cell, and the simulated caches decide
// the loads.
// A record of schema 9 or before (no lease names its more cells) is
// replayed as recorded in both phases.
bool cellsLogged(const ClusterRecord& record, int phase) {
  bool schema10 = false;
  for (const LeaseLogEntry& lease : record.leases) {
    schema10 = schema10 || lease.moreCellsLogged;
    if (lease.phase == phase && lease.moreCells > 0 && !lease.moreCellsLogged) return false;
  }
  return schema10;
}

// A worker's cache budget: its --memory less its own footprint and a
// lease's buffers (worker_session.cpp, cacheBudgetFor: 12 MiB of buffers,
// and 11 MiB resident at start, measured).
constexpr uint64_t kWorkerOwnBytes = uint64_t(23) << 20;
uint64_t workerCacheBudget(const ClusterModelOptions& options) {
  return options.workerMemoryBytes > 2 * kWorkerOwnBytes ? options.workerMemoryBytes - kWorkerOwnBytes
                                                          : options.workerMemoryBytes / 2;
}

// What a phase's leases measured, per cell: the work queued for it and its
// tracing's own seconds per unit of work and CPU share, and its loads' own
// seconds per triangle; and the phase's load seconds per triangle and CPU
// share of all its time.
struct PhaseCosts {
  bool cellsLogged = false;
  std::map<uint32_t, std::deque<Piece>> pieces;
  std::map<uint32_t, double> secondsPerWork, cpuShare, loadSecondsPerTriangle;
  double meanSecondsPerWork = 0, phaseLoadSecondsPerTriangle = 0, phaseCpuShare = 1;
  double photonFetchSeconds = 0;   // render phase, simulated caches: per cell new to its worker
};

// A lease's cells and the work of each: its own cell holds what its more
// cells do not.
std::vector<std::pair<uint32_t, int64_t>> cellWork(const LeaseLogEntry& lease, bool logged) {
  std::vector<std::pair<uint32_t, int64_t>> cells{{lease.cell, lease.work}};
  if (!logged) return cells;
  for (const auto& [cell, work] : lease.moreCellWork) {
    cells.emplace_back(cell, work);
    cells.front().second -= work;
  }
  cells.front().second = std::max<int64_t>(0, cells.front().second);
  return cells;
}

// A render lease on a cell whose photon map its worker lacks waits for the
// map's photons (FetchPhotons, a round trip through the coordinator, which
// reads them from the job's photon tables) before its timer starts: the
// record shows it as a gap on that worker between the previous Result and
// the lease's start (its Result less its own time). The mean of those gaps,
// on the leases of cells new to their worker.
double photonFetchSeconds(const ClusterRecord& record) {
  struct Last {
    int64_t resultMs = -1;
    std::set<uint32_t> cells;
  };
  std::map<std::string, Last> workers;
  double gaps = 0;
  int64_t fetches = 0;
  for (const LeaseLogEntry& lease : record.leases) {   // in the order Results came
    if (lease.phase != 1) continue;
    Last& last = workers[lease.worker];
    if (last.resultMs >= 0 && last.cells.insert(lease.cell).second) {
      gaps += std::max(0.0, double(lease.resultMs - last.resultMs) * 1e-3 - double(lease.leaseMicros) * 1e-6);
      ++fetches;
    }
    last.cells.insert(lease.cell);
    last.resultMs = lease.resultMs;
  }
  return fetches ? gaps / double(fetches) : 0;
}

PhaseCosts phaseCosts(const ClusterRecord& record, int phase, double workScale) {
  PhaseCosts costs;
  costs.cellsLogged = cellsLogged(record, phase);
  struct Measured {
    double seconds = 0, cpuSeconds = 0, loadSeconds = 0, loadTriangles = 0;
    int64_t work = 0;
  };
  std::map<uint32_t, Measured> measured;
  double loadSeconds = 0, triangles = 0, own = 0, cpu = 0;
  // The record's progress (its share of the phase's work done, the lease
  // log being in the order Results came) when each cell's latest lease came
  // back, and when each lease was sent.
  std::vector<std::pair<int64_t, int64_t>> doneAt;   // (result ms, work done then)
  for (const LeaseLogEntry& lease : record.leases)
    if (lease.phase == phase && lease.work > 0)
      doneAt.emplace_back(lease.resultMs, (doneAt.empty() ? 0 : doneAt.back().second) + lease.work);
  const double phaseWork = doneAt.empty() ? 1.0 : double(doneAt.back().second);
  const auto progressAt = [&](int64_t ms) {
    const auto it =
        std::upper_bound(doneAt.begin(), doneAt.end(), std::make_pair(ms, std::numeric_limits<int64_t>::max()));
    return it == doneAt.begin() ? 0.0 : double(std::prev(it)->second) / phaseWork;
  };
  int64_t doneWork = 0;
  std::map<uint32_t, double> backAt;
  for (const LeaseLogEntry& lease : record.leases) {
    if (lease.phase != phase || lease.work <= 0) continue;
    doneWork += lease.work;
    const OwnTime time = ownTime(lease);
    const double wall = double(lease.leaseMicros) * 1e-6;
    // Its loads' own time: their wall time as the lease's is its own.
    const double load = std::min(time.seconds, wall > 0 ? double(lease.loadMicros) * 1e-6 * time.seconds / wall : 0.0);
    const double trace = std::max(0.0, time.seconds - load);
    // Each cell's share of the lease's tracing is its share of the work;
    // its loads' seconds per triangle, the lease's (the log counts the
    // lease's loads, not whose). Unlogged, a lease of several cells counts
    // as its own cell's.
    const std::vector<std::pair<uint32_t, int64_t>> cells = cellWork(lease, costs.cellsLogged);
    for (const auto& [cell, work] : cells) {
      const double share = double(work) / double(lease.work);
      const int64_t scaled = std::max<int64_t>(1, std::llround(double(work) * workScale));
      // A cell's first piece is queued from the start; a later one once
      // the cell's previous lease came back, and no sooner than the record
      // leased it: photons come back to a cell through the others.
      const auto back = backAt.find(cell);
      const double releaseAt =
          !costs.cellsLogged || back == backAt.end() ? 0.0 : std::max(back->second, progressAt(lease.sentMs));
      if (work > 0 || cell == lease.cell)
        costs.pieces[cell].push_back({scaled, costs.cellsLogged ? 0.0 : load, releaseAt});
      Measured& m = measured[cell];
      m.seconds += trace * share;
      m.cpuSeconds += std::min(time.cpuSeconds, time.seconds) * share;
      m.work += work;
      if (lease.trianglesLoaded > 0) {
        m.loadSeconds += load;
        m.loadTriangles += double(lease.trianglesLoaded);
      }
    }
    for (const auto& [cell, work] : cells) backAt[cell] = double(doneWork) / phaseWork;
    loadSeconds += load;
    triangles += double(lease.trianglesLoaded);
    own += time.seconds;
    cpu += time.cpuSeconds;
  }
  costs.phaseLoadSecondsPerTriangle = triangles > 0 ? loadSeconds / triangles : 0;
  double rates = 0;
  for (const auto& [cell, m] : measured) {
    costs.secondsPerWork[cell] = m.seconds / double(std::max<int64_t>(1, m.work));
    rates += costs.secondsPerWork[cell];
    costs.cpuShare[cell] = m.seconds > 0 ? std::min(1.0, m.cpuSeconds / (m.seconds + 1e-12)) : 1.0;
    costs.loadSecondsPerTriangle[cell] =
        m.loadTriangles > 0 ? m.loadSeconds / m.loadTriangles : costs.phaseLoadSecondsPerTriangle;
  }
  costs.meanSecondsPerWork = measured.empty() ? 0 : rates / double(measured.size());
  costs.phaseCpuShare = own > 0 ? cpu / own : 1;
  if (phase == 1 && costs.cellsLogged) costs.photonFetchSeconds = photonFetchSeconds(record);
  return costs;
}

// The queue of one phase as JobStore keeps it: unleased pieces per cell,
// ranked by pending work (most first, ties: lower cell).
class ModelQueue {
 public:
  ModelQueue(std::map<uint32_t, std::deque<Piece>> pieces, int phase) : pieces_(std::move(pieces)), phase_(phase) {
    for (const auto& [cell, queue] : pieces_) {
      pending_[cell] = 0;
      released_[cell] = 0;
      for (const Piece& piece : queue) {
        unreleased_.push_back({piece.releaseAt, cell});
        total_ += piece.work;
      }
    }
    std::stable_sort(unreleased_.begin(), unreleased_.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    release(0);
  }
  bool empty() const { return ranked_.empty(); }
  // No work left, released or not.
  bool exhausted() const { return ranked_.empty() && next_ == unreleased_.size(); }
  int64_t totalWork() const { return total_; }
  // Releases the pieces due at `progress` (the share of the phase's work
  // done), or with `next`, those due next: what the workers' Results queue.
  void release(double progress, bool next = false) {
    if (next && next_ < unreleased_.size()) progress = std::max(progress, unreleased_[next_].first);
    for (; next_ < unreleased_.size() && unreleased_[next_].first <= progress; ++next_) {
      const uint32_t cell = unreleased_[next_].second;
      const Piece& piece = pieces_[cell][released_[cell]++];
      rank(cell, pending_[cell] + piece.work);
    }
  }
  std::vector<PendingCell> candidates(size_t limit) const {
    std::vector<PendingCell> result;
    for (auto it = ranked_.begin(); it != ranked_.end() && result.size() < limit; ++it)
      result.push_back({kModelJob, it->second, phase_, -it->first});
    return result;
  }
  // The oldest released pieces up to maxWork, at least some
  // (JobStore::openLease takes whole batches; a piece larger than maxWork,
  // a recorded lease scaled up, is cut as the coordinator's finer batches
  // would be). The loads of a piece go with its first part.
  Piece take(uint32_t cell, int64_t maxWork) {
    auto& queue = pieces_[cell];
    size_t& released = released_[cell];
    Piece taken;
    while (released > 0 && (taken.work == 0 || taken.work + queue.front().work <= maxWork)) {
      Piece& front = queue.front();
      const int64_t part = taken.work == 0 ? std::min(front.work, std::max<int64_t>(1, maxWork)) : front.work;
      taken.work += part;
      taken.loadSeconds += front.loadSeconds;
      front.loadSeconds = 0;
      front.work -= part;
      if (front.work > 0) break;
      queue.pop_front();
      --released;
    }
    rank(cell, pending_[cell] - taken.work);
    return taken;
  }

 private:
  void rank(uint32_t cell, int64_t work) {
    ranked_.erase({-pending_[cell], cell});
    pending_[cell] = work;
    if (released_[cell] > 0) ranked_.insert({-work, cell});
  }

  std::map<uint32_t, std::deque<Piece>> pieces_;
  std::map<uint32_t, int64_t> pending_;                  // released work
  std::map<uint32_t, size_t> released_;                  // released pieces, at the front of each queue
  std::vector<std::pair<double, uint32_t>> unreleased_;  // (when, cell), in the order they are due
  size_t next_ = 0;
  int64_t total_ = 0;
  std::set<std::pair<int64_t, uint32_t>> ranked_;
  int phase_;
};

// A lease as the model runs it: its own time on a worker (CPU, then the
// rest blocked) and its loads.
struct ModelLease {
  uint64_t id = 0;
  size_t worker = 0;
  double cpuSeconds = 0, blockedSeconds = 0, loadSeconds = 0;
  int64_t triangles = 0, work = 0;
  double startedAt = 0, wallSeconds = 0;
  double fetchSeconds = 0;   // waiting for its photons before its timer starts
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

// chooseCell is timed in this thread's CPU, not wall time: what it costs a
// coordinator, whatever else shares this machine's cores with the model.
double threadCpuSeconds() {
  timespec now{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return double(now.tv_sec) + double(now.tv_nsec) * 1e-9;
}

// Thread ids on the shared cores: the coordinator, then the workers.
constexpr size_t kCoordinatorThread = 0;

class PhaseSimulation {
 public:
  PhaseSimulation(const ClusterRecord& record, const ClusterModelOptions& options, int phase,
                  WorkerRegistry& registry, std::vector<ModelWorker>& workers, double startAt)
      : record_(record), options_(options), phase_(phase), costs_(phaseCosts(record, phase, phase == 0 ? options.workScale : 1.0)),
        queue_(costs_.pieces, phase), registry_(registry), workers_(workers), cores_(options.hostCores),
        now_(startAt) {}

  PhasePrediction run(uint64_t& nextLease, double& chooseSeconds, int64_t& chooseCalls) {
    nextLease_ = &nextLease;
    const double start = now_;
    dispatch();
    for (;;) {
      startIdleThreads();
      const double next = std::min(cores_.nextEnd(now_), events_.empty() ? cores_.nextEnd(now_) : events_.top().at);
      if (!std::isfinite(next)) {
        // Nothing in flight: what the record queued next is queued now.
        if (queue_.exhausted() || queue_.totalWork() == 0) break;
        queue_.release(double(doneWork_) / double(queue_.totalWork()), true);
        dispatch();
        continue;
      }
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
    prediction_.simulatedCaches = costs_.cellsLogged;
    chooseSeconds += chooseSeconds_;
    chooseCalls += chooseCalls_;
    return prediction_;
  }
  double endAt() const { return now_; }

 private:
  double perLease() const {
    return options_.coordinatorSecondsPerLease >= 0 ? options_.coordinatorSecondsPerLease
                                                    : record_.coordinatorSecondsPerLease;
  }
  // A lease's bytes on the coordinator's link.
  double linkSeconds(int64_t work) const {
    if (options_.bytesPerWork[phase_] <= 0 || options_.linkBytesPerSecond <= 0) return 0;
    return double(work) * options_.bytesPerWork[phase_] / options_.linkBytesPerSecond;
  }

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
    lease.wallSeconds = now_ - lease.startedAt - lease.fetchSeconds;
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
    doneWork_ += lease.work;
    queue_.release(double(doneWork_) / double(std::max<int64_t>(1, queue_.totalWork())));
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
    const double started = threadCpuSeconds();
    const PendingCell* chosen = chooseCell(candidates, record_.cells, info, registry_);
    const double chooseSeconds = threadCpuSeconds() - started;
    chooseSeconds_ += chooseSeconds;
    ++chooseCalls_;
    if (!chosen) return false;
    // A lease scale stretches the lease's target seconds and the
    // coordinator's cap on its work alike.
    const int64_t leaseWork = std::llround(options_.leaseScale * double(info.nextLeaseWork(kMaxLeaseWork)));
    const Piece first = queue_.take(chosen->cell, std::max<int64_t>(1, leaseWork));
    std::vector<std::pair<uint32_t, Piece>> cells{{chosen->cell, first}};
    const int64_t work = addMoreCells(
        candidates, *chosen, record_.cells, info, registry_, first.work, [](const PendingCell&) { return false; },
        [&](const PendingCell& c, int64_t maxWork) {
          const Piece taken = queue_.take(c.cell, maxWork);
          cells.emplace_back(c.cell, taken);
          return taken.work;
        });
    const double cost = perLease() / 2 + chooseSeconds + linkSeconds(work);
    prediction_.coordinatorBusySeconds += cost;
    const uint64_t lease = (*nextLease_)++;
    info.leases.emplace(lease, WorkerInfo::LeaseInFlight{toMs(now_), work, {}, {}});
    for (const auto& [cell, piece] : cells) info.cells.use(kModelJob, cell, cachedBytesOf(record_.cells, cell));
    ModelLease modelLease = leaseOf(w, lease, cells);
    modelLease.work = work;
    tasks_.push_back({false, modelLease, cost});
    ++prediction_.leases;
    return true;
  }

  // What the lease will take its worker: its cells' loads, then their
  // work, CPU first and then the time the record spent blocked. Worked out
  // as it is leased: a worker traces its leases in that order.
  ModelLease leaseOf(size_t w, uint64_t id, const std::vector<std::pair<uint32_t, Piece>>& cells) {
    ModelLease lease{id, w};
    double traceSeconds = 0, traceCpu = 0;
    for (const auto& [cell, piece] : cells) {
      if (!costs_.cellsLogged) loadAsRecorded(w, cell, piece, lease);
      // The photon map is loaded with the cell and taken as dropped with it.
      else if (loadInCache(w, cell, lease)) lease.fetchSeconds += costs_.photonFetchSeconds;
      const auto rate = costs_.secondsPerWork.find(cell);
      const double seconds =
          double(piece.work) * (rate != costs_.secondsPerWork.end() ? rate->second : costs_.meanSecondsPerWork);
      const auto share = costs_.cpuShare.find(cell);
      traceSeconds += seconds;
      traceCpu += seconds * (share != costs_.cpuShare.end() ? share->second : costs_.phaseCpuShare);
    }
    lease.cpuSeconds = traceCpu + lease.loadSeconds * costs_.phaseCpuShare;
    lease.blockedSeconds = std::max(0.0, traceSeconds + lease.loadSeconds - lease.cpuSeconds);
    // The wait for photons is mostly the worker's own: the reply received
    // and decoded on its main thread, the tracing thread woken: it runs on
    // the cores as CPU, slower when they are shared (with two workers and
    // the coordinator on two cores the record's gaps double).
    lease.cpuSeconds += lease.fetchSeconds;
    prediction_.workerBusySeconds += traceSeconds + lease.loadSeconds;
    return lease;
  }

  // The worker's cache keys a cell by its structure too: the render
  // phase's (bvh) is not the photon pass's (grid).
  uint64_t cacheKey() const { return uint64_t(phase_) + 1; }
  uint64_t cellTriangles(uint32_t cell) const {
    return cell < record_.cells.size() ? record_.cells[cell].triangleCount : 0;
  }
  uint64_t cellFileBytes(uint32_t cell) const {
    return cell < record_.cells.size() ? record_.cells[cell].byteCount : 0;
  }

  // The worker's cache as worker/cell_cache.cpp runs it: a cell it does not
  // hold is loaded, at the record's seconds per triangle for that cell,
  // after room is made for it, the least recently used going first, from
  // the worker's estimate of what it will take (CellCache::cell: the
  // larger of 3 and 1.5x the bytes per file byte it has seen); it then
  // takes its real bytes. Cells the lease in progress uses are pinned
  // there: here they are the most recently used, and a lease's more cells
  // are held to a quarter of the budget (addMoreCells), so the least
  // recently used order never reaches them either.
  bool loadInCache(size_t w, uint32_t cell, ModelLease& lease) {
    CellCacheModel& cache = workers_[w].cache;
    const double fileBytes = double(cellFileBytes(cell));
    const double perFileByte = options_.cachedBytesPerFileByte[phase_];
    const uint64_t bytes = uint64_t(perFileByte * fileBytes);
    if (cache.holds(cacheKey(), cell)) {
      cache.use(cacheKey(), cell, bytes);
      return false;
    }
    const uint64_t estimate = std::max(bytes, uint64_t(std::max(3.0, 1.5 * perFileByte) * fileBytes));
    const uint64_t budget = workerCacheBudget(options_);
    cache.setBudget(budget > estimate - bytes ? budget - (estimate - bytes) : 1);
    cache.use(cacheKey(), cell, bytes);
    cache.setBudget(budget);
    const auto rate = costs_.loadSecondsPerTriangle.find(cell);
    const double perTriangle =
        rate != costs_.loadSecondsPerTriangle.end() ? rate->second : costs_.phaseLoadSecondsPerTriangle;
    lease.loadSeconds += double(cellTriangles(cell)) * perTriangle;
    lease.triangles += int64_t(cellTriangles(cell));
    ++prediction_.loads;
    return true;
  }

  // From a record that does not name its leases' more cells: the record's
  // loads recur with the pieces that made them, and a cell another worker
  // loaded in this phase, missing from this worker's cache (an LRU of its
  // --memory), is loaded again: a second copy.
  void loadAsRecorded(size_t w, uint32_t cell, const Piece& piece, ModelLease& lease) {
    ModelWorker& worker = workers_[w];
    const bool loadedElsewhere = !loadedBy_[cell].empty() && !loadedBy_[cell].count(w);
    if (!worker.cache.holds(cacheKey(), cell)) {
      loadedBy_[cell].insert(w);
      if (loadedElsewhere) {
        const int64_t triangles = int64_t(cellTriangles(cell));
        lease.loadSeconds += double(triangles) * costs_.phaseLoadSecondsPerTriangle;
        lease.triangles += triangles;
        ++prediction_.loads;
      }
    }
    lease.loadSeconds += piece.loadSeconds;
    worker.cache.use(cacheKey(), cell, uint64_t(kCachedBytesPerFileByte * double(cellFileBytes(cell))));
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
  int64_t doneWork_ = 0;   // the work of the Results applied
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
    workers[w].cache.setBudget(cellsLogged(record, 0) ? workerCacheBudget(options) : options.workerMemoryBytes);
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
    const double change = phase == 1 ? record.phaseChangeSeconds : record.phaseStartSeconds;
    PhaseSimulation simulation(record, options, phase, registry, workers, at + change);
    prediction.phases[phase] = simulation.run(nextLease, chooseSeconds, chooseCalls);
    prediction.phases[phase].seconds += change;
    prediction.phases[phase].coordinatorBusySeconds += change;
    at += prediction.phases[phase].seconds;
  }
  prediction.chooseCellMicros = chooseCalls ? chooseSeconds * 1e6 / double(chooseCalls) : 0;
  prediction.chooseCellCalls = chooseCalls;
  return prediction;
}

}  // namespace portico
