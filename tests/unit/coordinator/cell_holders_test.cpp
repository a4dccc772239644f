// The registry's index of which workers hold each cell (CellHolders), and
// the cell choice that reads it: the same answers as walking every
// worker's cache model, on many workers with random caches.
#include <gtest/gtest.h>

#include <limits>
#include <random>
#include <set>
#include <string>

#include "coordinator/cell_choice.h"
#include "coordinator/cell_holders.h"
#include "coordinator/worker_registry.h"

namespace portico {
namespace {

// The reference: every other worker's model asked in turn.
struct ScannedHolders {
  bool any = false;
  bool freeWithin = false;
};
double speedOf(const WorkerInfo& worker) {
  return worker.workPerSecond > 0 ? worker.workPerSecond : kUnmeasuredWorkPerSecond;
}
ScannedHolders scanHolders(const WorkerInfo& worker, const WorkerRegistry& workers, uint64_t job, uint32_t cell,
                           double seconds) {
  ScannedHolders holders;
  for (const auto& [identity, other] : workers) {
    if (&other == &worker || !other.holds(job, cell)) continue;
    holders.any = true;
    if (!other.ready) continue;
    int64_t queued = 0;
    for (const auto& [id, lease] : other.leases) queued += lease.work;
    if (double(queued) / speedOf(other) < seconds) holders.freeWithin = true;
  }
  return holders;
}
const PendingCell* scannedChoice(const std::vector<PendingCell>& candidates, const std::vector<CellInfo>& cells,
                                 const WorkerInfo& worker, const WorkerRegistry& workers) {
  const double speed = speedOf(worker);
  const double loadSecondsPerTriangle =
      worker.loadSecondsPerTriangle > 0 ? worker.loadSecondsPerTriangle : kLoadSecondsPerTriangle;
  const PendingCell* chosen = nullptr;
  double best = -std::numeric_limits<double>::infinity();
  for (const PendingCell& c : candidates) {
    if (c.job != candidates.front().job) break;
    const bool mine = worker.holds(c.job, c.cell);
    const double triangles = c.cell < cells.size() ? double(cells[c.cell].triangleCount) : 0.0;
    const double loadSeconds = triangles * loadSecondsPerTriangle;
    const ScannedHolders holders = mine ? ScannedHolders{} : scanHolders(worker, workers, c.job, c.cell, loadSeconds);
    const double value = double(c.work) - (holders.any ? loadSeconds * speed : 0.0);
    if (value < 0 && holders.freeWithin) continue;
    if (value > best || (value == best && mine)) {
      best = value;
      chosen = &c;
    }
  }
  return chosen;
}
bool scannedMayJoin(const PendingCell& c, const PendingCell& chosen, const WorkerInfo& worker,
                    const WorkerRegistry& workers) {
  if (&c == &chosen || c.job != chosen.job || c.phase != chosen.phase) return false;
  return worker.holds(c.job, c.cell) || !scanHolders(worker, workers, c.job, c.cell, 0.0).any;
}

// Enough cells that most are held by one worker or none, where a stale
// holder would change a choice.
constexpr uint32_t kCells = 4000;
constexpr uint64_t kJobs = 2;

struct RandomCluster {
  std::mt19937_64 rng{20261125};
  WorkerRegistry workers;
  std::vector<CellInfo> cells;

  uint64_t below(uint64_t n) { return std::uniform_int_distribution<uint64_t>(0, n - 1)(rng); }
  void useCells(WorkerInfo& w, int uses) {
    for (int i = 0; i < uses; ++i) w.cells.use(1 + below(kJobs), uint32_t(below(kCells)), 1 + below(40));
  }
  void randomize(WorkerInfo& w) {
    w.ready = below(5) != 0;
    w.workPerSecond = below(4) == 0 ? 0 : double(1000 + below(1000000));
    w.loadSecondsPerTriangle = below(3) == 0 ? 0 : 1e-8 * double(1 + below(100));
    w.leases.clear();
    for (uint64_t l = 0, n = below(WorkerInfo::kMostLeasesInFlight + 1); l < n; ++l)
      w.leases.emplace(l, WorkerInfo::LeaseInFlight{0, int64_t(below(200000)), {}});
  }
  explicit RandomCluster(size_t count) {
    for (uint32_t c = 0; c < kCells; ++c) {
      cells.push_back({});
      cells.back().id = c;
      cells.back().triangleCount = below(500000);
    }
    for (size_t i = 0; i < count; ++i) {
      WorkerInfo& w = workers["worker-" + std::to_string(i)];
      w.cells.setBudget(below(4) == 0 ? 0 : 200 + below(3000));   // 0: kCellsWithoutBudget cells
      randomize(w);
      useCells(w, int(below(600)));
    }
  }
  std::vector<PendingCell> candidates() {
    std::vector<PendingCell> list(1 + below(kLeaseCandidates));
    for (PendingCell& c : list) c = {1 + below(kJobs), uint32_t(below(kCells)), int(below(2)), int64_t(below(300000))};
    std::sort(list.begin(), list.end(), [](const PendingCell& a, const PendingCell& b) { return a.work > b.work; });
    return list;
  }
};

std::set<const WorkerInfo*> scannedHoldersOf(const WorkerRegistry& workers, uint64_t job, uint32_t cell) {
  std::set<const WorkerInfo*> holders;
  for (const auto& [identity, w] : workers)
    if (w.holds(job, cell)) holders.insert(&w);
  return holders;
}

void expectIndexMatchesScan(const WorkerRegistry& workers) {
  for (uint64_t job = 1; job <= kJobs; ++job)
    for (uint32_t cell = 0; cell < kCells; ++cell) {
      const auto& indexed = workers.holdersOf(job, cell);
      const std::set<const WorkerInfo*> unique(indexed.begin(), indexed.end());
      ASSERT_EQ(unique.size(), indexed.size()) << "job " << job << " cell " << cell << " listed twice";
      ASSERT_EQ(unique, scannedHoldersOf(workers, job, cell)) << "job " << job << " cell " << cell;
    }
}

TEST(CellHolders, FollowsEveryModelThroughUseEvictionErasureAndReplacement) {
  RandomCluster cluster(96);
  expectIndexMatchesScan(cluster.workers);
  // A worker leaves, another's model is replaced, one takes another's whole
  // record, and a copy taken out of the registry comes and goes.
  cluster.workers.erase(cluster.workers.find("worker-3"));
  cluster.workers.at("worker-5").cells = CellCacheModel(500);
  cluster.useCells(cluster.workers.at("worker-5"), 50);
  cluster.workers.at("worker-7") = cluster.workers.at("worker-8");
  { WorkerInfo copy = cluster.workers.at("worker-9"); cluster.useCells(copy, 100); }
  WorkerInfo& late = cluster.workers["late"];
  cluster.useCells(late, 300);
  for (auto& [identity, w] : cluster.workers) cluster.useCells(w, 20);
  expectIndexMatchesScan(cluster.workers);
  cluster.workers.at("worker-7").cells.use(1, 17, 1);
  EXPECT_TRUE(cluster.workers.at("worker-7").holds(1, 17));
  EXPECT_FALSE(cluster.workers.at("worker-8").holds(1, 17) && cluster.workers.holdersOf(1, 17).size() < 2);
  expectIndexMatchesScan(cluster.workers);
}

TEST(CellHolders, ChooseCellAndMayJoinLeaseAnswerAsTheScanDoes) {
  RandomCluster cluster(128);
  size_t choices = 0, none = 0, splits = 0;
  for (int round = 0; round < 60; ++round) {
    const std::vector<PendingCell> candidates = cluster.candidates();
    for (const auto& [identity, w] : cluster.workers) {
      if (cluster.below(8) != 0) continue;
      const PendingCell* indexed = chooseCell(candidates, cluster.cells, w, cluster.workers);
      ASSERT_EQ(indexed, scannedChoice(candidates, cluster.cells, w, cluster.workers)) << identity << " round " << round;
      ++choices;
      if (!indexed) { ++none; continue; }
      splits += !w.holds(indexed->job, indexed->cell) && !scannedHoldersOf(cluster.workers, indexed->job, indexed->cell).empty();
      for (const PendingCell& c : candidates)
        ASSERT_EQ(mayJoinLease(c, *indexed, w, cluster.workers, false), scannedMayJoin(c, *indexed, w, cluster.workers));
    }
    // The cluster moves on: leases change hands and caches turn over.
    for (auto& [identity, w] : cluster.workers) {
      if (cluster.below(3) != 0) continue;
      cluster.randomize(w);
      cluster.useCells(w, int(cluster.below(40)));
    }
  }
  // The cases the index must get right all occur: a choice, none (left to a
  // holder), a cell split with its holder.
  EXPECT_GT(choices, 500u);
  EXPECT_GT(none + splits, 0u);
}

}  // namespace
}  // namespace portico
