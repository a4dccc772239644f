// The coordinator's choice of a lease's cell, and its model of what each
// worker holds.
#include <gtest/gtest.h>

#include "coordinator/cell_choice.h"
#include "coordinator/cell_cache_model.h"

namespace portico {
namespace {

std::vector<CellInfo> cellsOf(std::vector<uint64_t> triangles) {
  std::vector<CellInfo> cells(triangles.size());
  for (size_t i = 0; i < cells.size(); ++i) {
    cells[i].id = uint32_t(i);
    cells[i].triangleCount = triangles[i];
  }
  return cells;
}

struct TwoWorkers {
  WorkerRegistry workers;
  WorkerInfo& a;
  WorkerInfo& b;
  TwoWorkers() : a(workers["a"]), b(workers["b"]) {
    a.identity = "a";
    b.identity = "b";
    a.workPerSecond = b.workPerSecond = 1e6;   // a load of T triangles: T / 10 rays
  }
};

TEST(ChooseCell, TakesTheMostWorkWhenNoCopyIsNeeded) {
  TwoWorkers w;
  const auto cells = cellsOf({1000, 450000, 1000});
  w.a.cells.use(1, 0, 1);
  // Cell 1 is big and nobody holds it: loading it is due some time anyway,
  // so it is not deferred behind the small cell the worker holds.
  const std::vector<PendingCell> candidates{{1, 1, 0, 5000}, {1, 0, 0, 200}};
  EXPECT_EQ(chooseCell(candidates, cells, w.a, w.workers)->cell, 1u);
}

TEST(ChooseCell, SplitsAnothersCellOnlyWhenItsWorkOutweighsASecondLoad) {
  TwoWorkers w;
  const auto cells = cellsOf({100000, 1000});   // a second load of cell 0: 10 000 rays
  w.b.cells.use(1, 0, 1);
  const std::vector<PendingCell> small{{1, 0, 0, 9000}, {1, 1, 0, 100}};
  EXPECT_EQ(chooseCell(small, cells, w.a, w.workers)->cell, 1u);
  const std::vector<PendingCell> large{{1, 0, 0, 20000}, {1, 1, 0, 100}};
  EXPECT_EQ(chooseCell(large, cells, w.a, w.workers)->cell, 0u);
  // The worker holding it takes it whatever its size.
  EXPECT_EQ(chooseCell(small, cells, w.b, w.workers)->cell, 0u);
  // With nothing else pending, even a small queue of another's cell is split
  // when its holder is not free for it: a worker never waits while there is work.
  const std::vector<PendingCell> only{{1, 0, 0, 10}};
  EXPECT_EQ(chooseCell(only, cells, w.a, w.workers)->cell, 0u);
}

TEST(ChooseCell, WeighsASecondLoadAtTheWorkersMeasuredLoadCost) {
  TwoWorkers w;
  const auto cells = cellsOf({100000, 1000});
  w.b.cells.use(1, 0, 1);
  const std::vector<PendingCell> candidates{{1, 0, 0, 20000}, {1, 1, 0, 100}};
  // Unmeasured: the default cost (10 000 rays) is outweighed by 20 000.
  EXPECT_EQ(chooseCell(candidates, cells, w.a, w.workers)->cell, 0u);
  // a's Results say its loads take 0.4 us a triangle (an Embree build, say):
  // a second load of cell 0 is now worth 40 000 rays, more than its queue.
  w.a.recordLoads(50000, 20000);
  EXPECT_DOUBLE_EQ(w.a.loadSecondsPerTriangle, 4e-7);
  EXPECT_EQ(chooseCell(candidates, cells, w.a, w.workers)->cell, 1u);
  // Loads too small to time well teach nothing.
  w.a.recordLoads(500, 1);
  EXPECT_DOUBLE_EQ(w.a.loadSecondsPerTriangle, 4e-7);
  // Later loads are folded in.
  w.a.recordLoads(100000, 10000);
  EXPECT_DOUBLE_EQ(w.a.loadSecondsPerTriangle, 0.7 * 4e-7 + 0.3 * 1e-7);
}

TEST(ChooseCell, LeavesASmallQueueToAHolderThatIsFreeSooner) {
  TwoWorkers w;
  const auto cells = cellsOf({100000, 1000});   // a second load of cell 0: 10 ms, 10 000 rays
  w.b.cells.use(1, 0, 1);
  w.b.ready = true;
  const std::vector<PendingCell> only{{1, 0, 0, 10}};
  // b is idle: it takes the 10 rays at once, without a load.
  EXPECT_EQ(chooseCell(only, cells, w.a, w.workers), nullptr);
  EXPECT_EQ(chooseCell(only, cells, w.b, w.workers)->cell, 0u);
  // Another candidate that nobody holds still goes to a.
  const std::vector<PendingCell> two{{1, 0, 0, 10}, {1, 1, 0, 5}};
  EXPECT_EQ(chooseCell(two, cells, w.a, w.workers)->cell, 1u);
  // b is busy for 50 ms, longer than a's load: a takes it after all.
  w.b.leases[7] = {0, 50000};
  EXPECT_EQ(chooseCell(only, cells, w.a, w.workers)->cell, 0u);
  // A queue that outweighs the load is split whatever b does.
  w.b.leases.clear();
  const std::vector<PendingCell> large{{1, 0, 0, 20000}};
  EXPECT_EQ(chooseCell(large, cells, w.a, w.workers)->cell, 0u);
}

TEST(ChooseCell, PrefersItsOwnCellOnATieAndKeepsToTheFirstJob) {
  TwoWorkers w;
  const auto cells = cellsOf({1000, 1000, 1000});
  w.a.cells.use(1, 2, 1);
  const std::vector<PendingCell> tie{{1, 0, 0, 500}, {1, 2, 0, 500}};
  EXPECT_EQ(chooseCell(tie, cells, w.a, w.workers)->cell, 2u);
  // Job 2's cell has more work, but job 1 came first.
  const std::vector<PendingCell> jobs{{1, 0, 0, 500}, {2, 1, 0, 90000}};
  EXPECT_EQ(chooseCell(jobs, cells, w.a, w.workers)->job, 1u);
}

TEST(MayJoinLease, TakesCellsItHoldsOrNobodyHoldsOfTheSameJobAndPhase) {
  TwoWorkers w;
  w.a.cells.use(1, 1, 1);   // a holds cell 1
  w.b.cells.use(1, 2, 1);   // b holds cell 2; nobody holds 3
  const std::vector<PendingCell> pending{{1, 0, 0, 500}, {1, 1, 0, 400}, {1, 2, 0, 300}, {1, 3, 0, 200},
                                         {2, 3, 0, 100}, {1, 4, 1, 100}};
  const PendingCell& chosen = pending[0];
  EXPECT_FALSE(mayJoinLease(pending[0], chosen, w.a, w.workers, false));   // the lease's own cell
  EXPECT_TRUE(mayJoinLease(pending[1], chosen, w.a, w.workers, false));    // a holds it
  EXPECT_FALSE(mayJoinLease(pending[2], chosen, w.a, w.workers, false));   // b holds it: a second copy
  EXPECT_TRUE(mayJoinLease(pending[3], chosen, w.a, w.workers, false));    // nobody holds it
  EXPECT_FALSE(mayJoinLease(pending[4], chosen, w.a, w.workers, false));   // another job
  EXPECT_FALSE(mayJoinLease(pending[5], chosen, w.a, w.workers, false));   // another phase
  EXPECT_FALSE(mayJoinLease(pending[1], chosen, w.a, w.workers, true));    // it failed before
  // And b, by the same rule, takes cell 2 and cell 3 but not cell 1.
  EXPECT_FALSE(mayJoinLease(pending[1], chosen, w.b, w.workers, false));
  EXPECT_TRUE(mayJoinLease(pending[2], chosen, w.b, w.workers, false));
  EXPECT_TRUE(mayJoinLease(pending[3], chosen, w.b, w.workers, false));
}

TEST(CellCacheModel, ForgetsTheLeastRecentlyUsedBeyondTheBudget) {
  CellCacheModel model(1000);
  model.use(1, 0, 400);
  model.use(1, 1, 400);
  model.use(1, 0, 400);   // cell 0 used again: cell 1 is now the oldest
  model.use(1, 2, 400);   // 1200 > 1000: cell 1 goes
  EXPECT_TRUE(model.holds(1, 0));
  EXPECT_FALSE(model.holds(1, 1));
  EXPECT_TRUE(model.holds(1, 2));
  EXPECT_FALSE(model.holds(2, 0));   // jobs are told apart
  EXPECT_EQ(model.bytes(), 800u);
  // A cell over the whole budget is still held: the worker holds the cell it traces.
  model.use(1, 3, 5000);
  EXPECT_EQ(model.size(), 1u);
  EXPECT_TRUE(model.holds(1, 3));
}

TEST(CellCacheModel, WithoutABudgetKeepsAFixedNumberOfCells) {
  CellCacheModel model;
  for (uint32_t cell = 0; cell < CellCacheModel::kCellsWithoutBudget + 10; ++cell) model.use(1, cell, 1 << 20);
  EXPECT_EQ(model.size(), CellCacheModel::kCellsWithoutBudget);
  EXPECT_FALSE(model.holds(1, 9));
  EXPECT_TRUE(model.holds(1, 10));
}

}  // namespace
}  // namespace portico
