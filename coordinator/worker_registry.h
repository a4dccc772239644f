// The workers the coordinator has heard from: liveness, what they hold, and
// whether they are waiting for work.
#pragma once

#include <algorithm>
#include <cstdint>
#include <deque>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "coordinator/cell_cache_model.h"
#include "coordinator/result_check.h"

namespace portico {

struct WorkerInfo {
  std::string identity;       // ZeroMQ routing id
  std::string name;
  uint32_t cores = 1;
  uint64_t memoryBytes = 0;
  std::vector<std::string> tags;   // its pools (Hello.tags), sorted: jobs requiring tags it lacks are not its
  int64_t lastSeenMs = 0;
  bool ready = false;         // sent Ready: it takes leases
  // Whether its leases move (Coordinator::checkLeaseProgress): the progress
  // its heartbeats last reported, when it last showed progress (steady
  // clock), the lease its tracing thread is in (0: none), and since when it
  // is taken for stuck (0: it is not), with why; meanwhile it gets no lease.
  uint64_t progress = 0;
  int64_t progressMs = 0;
  uint64_t tracingLease = 0;
  int64_t stalledSinceMs = 0;
  std::string stallReason;
  // Its leases in flight: when each was sent, and the work it holds.
  struct LeaseInFlight {
    int64_t sentMs = 0;
    int64_t work = 0;
    // Each more cell and the work taken from its queue: logged with the
    // lease (LeaseLogEntry) for the cluster model; never read to schedule.
    std::vector<std::pair<uint32_t, int64_t>> moreCellWork;
    LeaseExpectation expected;   // what its Result must add up to (result_check.h)
    uint64_t job = 0;            // shown by status (the dashboard's workers table)
    uint32_t cell = 0;
    int phase = 0;
  };
  std::map<uint64_t, LeaseInFlight> leases;
  // A worker holds up to two leases: the next one is on its way (or already
  // queued there) while it traces the current one, so it never waits for
  // the round trip through the coordinator. Leases hold a cell's pending
  // work, often well under the second they may hold, and that round trip
  // would be about a fifth of a worker's time in a photon pass.
  static constexpr size_t kLeasesInFlight = 2;
  // Tiny leases (the end of a photon pass: a few photons per cell) are
  // over before the next one can arrive: a worker is kept up to
  // kMostLeasesInFlight of them while what it holds is under
  // kQueuedSeconds of its work.
  static constexpr size_t kMostLeasesInFlight = 8;
  static constexpr double kQueuedSeconds = 0.005;
  bool wantsLease() const {
    if (!ready || stalledSinceMs != 0) return false;
    if (leases.size() < kLeasesInFlight) return true;
    if (leases.size() >= kMostLeasesInFlight || workPerSecond <= 0) return false;
    int64_t held = 0;
    for (const auto& [id, lease] : leases) held += lease.work;
    return double(held) < workPerSecond * kQueuedSeconds;
  }
  bool idle() const { return ready && leases.empty() && stalledSinceMs == 0; }   // shown by status
  // What it holds ends within kRefillSeconds of its work (or it holds
  // nothing): its next lease should leave before the Results just in are
  // applied (Coordinator::runRound), not after.
  static constexpr double kRefillSeconds = 0.05;
  bool runsShort() const {
    if (leases.empty() || workPerSecond <= 0) return true;
    int64_t held = 0;
    for (const auto& [id, lease] : leases) held += lease.work;
    return double(held) < workPerSecond * kRefillSeconds;
  }
  CellCacheModel cells;        // what it likely holds
  // Lease sizing: about kLeaseSeconds of this worker's measured speed.
  double workPerSecond = 0;   // rays (photons, pixel samples) per second; 0 until measured
  int64_t lastResultMs = 0;   // when its last Result arrived
  // Shown by status: Results applied so far (the dashboard's leases per
  // second) and the largest resident memory its Results reported.
  int64_t leasesDone = 0;
  int64_t peakResidentBytes = 0;

  static constexpr double kLeaseSeconds = 1.0;
  static constexpr int64_t kMinLeaseWork = 1000;
  // The work to put in its next lease, at most `maxWork`.
  int64_t nextLeaseWork(int64_t maxWork) const {
    if (workPerSecond <= 0) return std::min<int64_t>(maxWork, 10 * kMinLeaseWork);   // a first, short lease to measure
    return std::clamp<int64_t>(int64_t(workPerSecond * kLeaseSeconds), std::min(kMinLeaseWork, maxWork), maxWork);
  }
  // A lease's Result arrived: fold its speed into the estimate. The worker
  // says how long the lease took it (`workerMicros`, 0 from a worker that
  // does not); a photon pass's leases last a few milliseconds, too short to
  // time from here, where the round trip and the queue dominate, so that
  // the speed stayed unmeasured (0) for half a pass, and a third of the
  // true one after. Without the worker's figure a lease is timed here,
  // from the later of its sending and the previous Result (a queued lease
  // starts when the one before it ends), when it took 20 ms or more.
  void recordLease(uint64_t lease, int64_t nowMs, int64_t workerMicros = 0) {
    auto it = leases.find(lease);
    const int64_t previousResultMs = lastResultMs;
    lastResultMs = nowMs;
    if (it == leases.end() || it->second.work <= 0) return;
    double rate;
    if (workerMicros >= 1000) {
      rate = double(it->second.work) * 1e6 / double(workerMicros);
    } else {
      const int64_t elapsed = nowMs - std::max(it->second.sentMs, previousResultMs);
      if (elapsed < 20) return;
      rate = double(it->second.work) * 1000.0 / double(elapsed);
    }
    foldIn(workPerSecond, rate);
  }

  // What loading a cell costs it, per triangle (read and accelerator
  // build): 0 until a Result reports a load of at least kMinTimedLoadTriangles.
  // It depends on the accelerator (a grid builds ~5x faster than Embree's
  // BVH here) and on the machine, so it is measured rather than assumed.
  double loadSecondsPerTriangle = 0;
  static constexpr int64_t kMinTimedLoadTriangles = 10000;
  void recordLoads(int64_t triangles, int64_t micros) {
    if (triangles < kMinTimedLoadTriangles || micros <= 0) return;
    foldIn(loadSecondsPerTriangle, double(micros) * 1e-6 / double(triangles));
  }

  bool holds(uint64_t job, uint32_t cell) const { return cells.holds(job, cell); }

 private:
  // An estimate (0: none yet) follows its measurements with a memory of a
  // few: the first one taken as it is, each later one weighing 30 %.
  static void foldIn(double& estimate, double measured) {
    estimate = estimate <= 0 ? measured : 0.7 * estimate + 0.3 * measured;
  }
};

// The workers by identity, and which of them hold each cell: each worker's
// model keeps the index as it takes cells in and evicts them, and leaves it
// when the worker is erased (CellHolders).
class WorkerRegistry {
 public:
  using Map = std::map<std::string, WorkerInfo>;
  using iterator = Map::iterator;
  using const_iterator = Map::const_iterator;

  WorkerRegistry() = default;
  WorkerRegistry(const WorkerRegistry&) = delete;   // its workers' models point at its index
  WorkerRegistry& operator=(const WorkerRegistry&) = delete;

  // The worker of that identity, added if it is new.
  WorkerInfo& operator[](const std::string& identity) {
    const auto [it, added] = workers_.try_emplace(identity);
    if (added) it->second.cells.attach(&holders_, &it->second);
    return it->second;
  }
  WorkerInfo& at(const std::string& identity) { return workers_.at(identity); }
  const WorkerInfo& at(const std::string& identity) const { return workers_.at(identity); }
  iterator find(const std::string& identity) { return workers_.find(identity); }
  const_iterator find(const std::string& identity) const { return workers_.find(identity); }
  size_t count(const std::string& identity) const { return workers_.count(identity); }
  iterator erase(iterator it) { return workers_.erase(it); }
  iterator begin() { return workers_.begin(); }
  iterator end() { return workers_.end(); }
  const_iterator begin() const { return workers_.begin(); }
  const_iterator end() const { return workers_.end(); }
  size_t size() const { return workers_.size(); }
  bool empty() const { return workers_.empty(); }

  // The workers whose models hold the cell, in no particular order.
  const CellHolders::Workers& holdersOf(uint64_t job, uint32_t cell) const {
    return holders_.of(CellCacheModel::key(job, cell));
  }

 private:
  CellHolders holders_;   // declared first: the workers' models leave it as they go
  Map workers_;
};

}  // namespace portico
