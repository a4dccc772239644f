#include "coordinator/cluster_model.h"
#include "coordinator/shared_cores.h"

#include <gtest/gtest.h>

namespace portico {
namespace {

// Cells 0 to count - 1 of 10 000 triangles in 400 000 bytes each.
void addCells(ClusterRecord& record, uint32_t count) {
  for (uint32_t c = 0; c < count; ++c) {
    CellInfo info;
    info.id = c;
    info.triangleCount = 10000;
    info.byteCount = 400000;
    record.cells.push_back(info);
  }
}

// A record of `cells` cells, each with `leasesPerCell` photon leases of
// 10 000 work taking 50 ms each and a render lease of 10 000 taking 20 ms;
// each cell 10 000 triangles loaded in 1 ms. `waited`: the share of each
// lease's wall time it spent waiting for a core (CPU recorded; -1: a
// record without CPU, schema 8).
ClusterRecord uniformRecord(uint32_t cells, int leasesPerCell, double coordinatorSecondsPerLease,
                            double waited = -1) {
  ClusterRecord record;
  addCells(record, cells);
  for (uint32_t c = 0; c < cells; ++c) {
    for (int k = 0; k < leasesPerCell; ++k)
      record.leases.push_back({1, 0, 0, c, 0, 10000, "w", 0, 0, k == 0 ? 51000 : 50000, k == 0 ? 1000 : 0,
                               k == 0 ? 1 : 0, k == 0 ? 10000 : 0});
    record.leases.push_back({1, 0, 1, c, 0, 10000, "w", 0, 0, 21000, 1000, 1, 10000});
  }
  if (waited >= 0)
    for (LeaseLogEntry& lease : record.leases) {
      // The same own time, stretched by the wait: wall = own / (1 - waited).
      const int64_t own = lease.leaseMicros;
      lease.leaseMicros = std::llround(double(own) / (1 - waited));
      lease.loadMicros = std::llround(double(lease.loadMicros) / (1 - waited));
      lease.cpuMicros = own;
      lease.runQueueMicros = lease.leaseMicros - own;
    }
  record.coordinatorSecondsPerLease = coordinatorSecondsPerLease;
  return record;
}

// A record that names its leases' cells (schema 10): `rounds` photon leases
// per cell, taken round after round over the cells (photons wander back to
// each cell after the others), 10 000 work in 50 ms each, the first of each
// cell loading it (10 000 triangles in 20 ms); then a render lease per cell.
ClusterRecord roundsRecord(uint32_t cells, int rounds) {
  ClusterRecord record;
  addCells(record, cells);
  const auto lease = [&](int phase, uint32_t cell, bool loads, int64_t resultMs) {
    LeaseLogEntry entry;
    entry.job = 1;
    entry.phase = phase;
    entry.cell = cell;
    entry.work = 10000;
    entry.worker = "w";
    entry.sentMs = resultMs - 50;
    entry.resultMs = resultMs;
    entry.leaseMicros = loads ? 70000 : 50000;
    entry.loadMicros = loads ? 20000 : 0;
    entry.cellsLoaded = loads ? 1 : 0;
    entry.trianglesLoaded = loads ? 10000 : 0;
    entry.moreCellsLogged = true;
    record.leases.push_back(entry);
  };
  int64_t at = 0;
  for (int k = 0; k < rounds; ++k)
    for (uint32_t c = 0; c < cells; ++c) lease(0, c, k == 0, at += 50);
  for (uint32_t c = 0; c < cells; ++c) lease(1, c, true, at += 50);
  record.coordinatorSecondsPerLease = 1e-4;
  return record;
}

TEST(ClusterModel, AWorkerWhoseCacheCannotHoldTheCellsReloadsThemOneThatCanDoesNot) {
  const uint32_t cells = 32;
  const int rounds = 4;
  const ClusterRecord record = roundsRecord(cells, rounds);
  ClusterModelOptions options;
  options.workers = 1;
  options.workerMemoryBytes = uint64_t(1) << 30;   // every cell, in both structures
  const ClusterPrediction holdsAll = simulateCluster(record, options);
  EXPECT_TRUE(holdsAll.phases[0].simulatedCaches);
  EXPECT_EQ(holdsAll.phases[0].loads, cells);   // each cell once: its later rounds find it
  EXPECT_EQ(holdsAll.phases[1].loads, cells);   // the render's structure is another
  // Room for about eight of the 32 cells (1.2 MB each, 1.8 MB made room
  // for) beside the worker's own 23 MiB: each round finds its cell dropped.
  options.workerMemoryBytes = (uint64_t(23) << 20) + 10'000'000;
  const ClusterPrediction small = simulateCluster(record, options);
  EXPECT_EQ(small.phases[0].loads, int64_t(cells) * rounds);
  // Each reload costs what the record's loads of that cell took: 20 ms.
  const double reloads = double(small.phases[0].loads - holdsAll.phases[0].loads);
  EXPECT_NEAR(small.phases[0].seconds - holdsAll.phases[0].seconds, reloads * 0.020, 0.1 * reloads * 0.020);
  // Two such workers hold twice the cells, and reload less than one does.
  options.workers = 2;
  options.workerMemoryBytes = (uint64_t(23) << 20) + 25'000'000;
  const ClusterPrediction twoWorkers = simulateCluster(record, options);
  options.workers = 1;
  options.workerMemoryBytes = (uint64_t(23) << 20) + 25'000'000;
  const ClusterPrediction oneWorker = simulateCluster(record, options);
  EXPECT_LT(twoWorkers.phases[0].loads, oneWorker.phases[0].loads);
}

TEST(SharedCores, ThreadsBeyondTheCoresShareThemEqually) {
  SharedCores two(2);
  two.start(0, 1.0);
  two.start(1, 1.0);
  two.start(2, 2.0);
  // Three threads on two cores: 2/3 of a core each; the 1 s bursts end at 1.5 s.
  EXPECT_NEAR(two.nextEnd(0), 1.5, 1e-9);
  const auto first = two.advance(0, 1.5);
  EXPECT_EQ(first.size(), 2u);
  // Alone, the third runs at a full core: its last second ends at 2.5 s.
  EXPECT_NEAR(two.nextEnd(1.5), 2.5, 1e-9);
  EXPECT_EQ(two.advance(1.5, 2.5), std::vector<size_t>{2});
  EXPECT_TRUE(two.idle());
  SharedCores cluster(0);   // a core each, however many
  for (size_t t = 0; t < 8; ++t) cluster.start(t, 1.0);
  EXPECT_NEAR(cluster.nextEnd(3), 4, 1e-9);
}

TEST(ClusterModel, ALeaseCostsItsOwnTimeNotWhatWaitingForACoreAddedToIt) {
  ClusterModelOptions options;
  const ClusterPrediction alone = simulateCluster(uniformRecord(32, 2, 1e-4), options);
  // The same leases measured while they waited half their wall time.
  const ClusterPrediction waited = simulateCluster(uniformRecord(32, 2, 1e-4, 0.5), options);
  EXPECT_NEAR(waited.seconds(), alone.seconds(), 0.02 * alone.seconds());
}

TEST(ClusterModel, WorkersSharingTheCoresOfOneMachineShareItsSpeed) {
  const ClusterRecord record = uniformRecord(64, 4, 1e-4, 0.0);
  ClusterModelOptions options;
  options.workers = 1;
  options.hostCores = 2;
  const double one = simulateCluster(record, options).seconds();
  options.workers = 2;
  const double two = simulateCluster(record, options).seconds();
  EXPECT_NEAR(two, one / 2, 0.1 * one / 2);   // a core each (the coordinator is nearly idle)
  options.hostCores = 1;
  const double twoOnOneCore = simulateCluster(record, options).seconds();
  EXPECT_NEAR(twoOnOneCore, one, 0.1 * one);   // no faster than one worker
  // Four workers on two cores: as two.
  options.workers = 4;
  options.hostCores = 2;
  EXPECT_NEAR(simulateCluster(record, options).seconds(), two, 0.1 * two);
}

TEST(ClusterModel, AWorkScaleMultipliesThePhotonPassTracingAndKeepsItsLoadsAndTheRender) {
  const ClusterRecord record = uniformRecord(64, 4, 1e-4, 0.0);
  ClusterModelOptions options;
  options.workers = 2;
  const ClusterPrediction base = simulateCluster(record, options);
  options.workScale = 1;
  EXPECT_DOUBLE_EQ(simulateCluster(record, options).phases[0].workerBusySeconds, base.phases[0].workerBusySeconds);
  options.workScale = 2;
  const ClusterPrediction doubled = simulateCluster(record, options);
  // Photon leases: 4 x 49 ms of tracing and one 1 ms load per cell, the
  // tracing doubled; render (20 ms and a load per cell): the same image.
  const double photonLoads = 64 * 0.001;
  EXPECT_NEAR(doubled.phases[0].workerBusySeconds - photonLoads, 2 * (base.phases[0].workerBusySeconds - photonLoads),
              0.02 * base.phases[0].workerBusySeconds);
  EXPECT_NEAR(doubled.phases[0].seconds, 2 * base.phases[0].seconds, 0.1 * base.phases[0].seconds);
  EXPECT_DOUBLE_EQ(doubled.phases[1].workerBusySeconds, base.phases[1].workerBusySeconds);
}

TEST(ClusterModel, OneWorkerTakesItsLeasesTimeAndMoreWorkersShareIt) {
  const ClusterRecord record = uniformRecord(64, 4, 1e-4);
  ClusterModelOptions options;
  options.workers = 1;
  const ClusterPrediction one = simulateCluster(record, options);
  // 64 cells x (4 x 50 ms + 1 ms load) photons, 64 x (20 ms + 1 ms) render.
  EXPECT_NEAR(one.phases[0].seconds, 64 * 0.201, 0.05 * 64 * 0.201);
  EXPECT_NEAR(one.phases[1].seconds, 64 * 0.021, 0.10 * 64 * 0.021);
  EXPECT_EQ(one.phases[0].loads, 0);   // one worker: the record's own loads, no second copies
  options.workers = 4;
  const ClusterPrediction four = simulateCluster(record, options);
  EXPECT_NEAR(four.seconds(), one.seconds() / 4, 0.15 * one.seconds() / 4);
  EXPECT_GT(four.workerUtilization(4), 0.8);
  EXPECT_LT(four.phases[0].loads, 16);   // a few cells split between workers at most
  EXPECT_LT(four.coordinatorUtilization(), 0.1);
}

TEST(ClusterModel, ACoordinatorSlowerThanItsWorkersBecomesTheBottleneck) {
  // 40 ms of coordinator per lease against 50 ms leases: beyond a couple of
  // workers, more workers wait instead of tracing.
  const ClusterRecord record = uniformRecord(64, 4, 0.04);
  ClusterModelOptions options;
  options.workers = 2;
  const ClusterPrediction two = simulateCluster(record, options);
  options.workers = 16;
  const ClusterPrediction sixteen = simulateCluster(record, options);
  EXPECT_GT(sixteen.coordinatorUtilization(), 0.9);
  EXPECT_LT(sixteen.workerUtilization(16), 0.3);
  EXPECT_GT(sixteen.seconds(), two.seconds() / 4);   // far from the 8x of 8x the workers
}

TEST(ClusterModel, AMeasuredCoordinatorCostReplacesTheRecordsAndItsBytesHoldTheLink) {
  // The record's coordinator is cheap (0.1 ms a lease); charged 40 ms of
  // CPU per lease instead, or 400 bytes per unit of work on a 100 MB/s
  // link (4 ms per 1 000 work, as much as the workers take: 16 workers at
  // 10 000 work per 50 ms trace 16 times faster than the link moves it),
  // 16 workers wait for it.
  const ClusterRecord record = uniformRecord(64, 4, 1e-4);
  ClusterModelOptions options;
  options.workers = 16;
  const ClusterPrediction recorded = simulateCluster(record, options);
  EXPECT_LT(recorded.coordinatorUtilization(), 0.2);
  options.coordinatorSecondsPerLease = 0.04;
  const ClusterPrediction slowCpu = simulateCluster(record, options);
  EXPECT_GT(slowCpu.coordinatorUtilization(), 0.9);
  EXPECT_GT(slowCpu.seconds(), 3 * recorded.seconds());
  options.coordinatorSecondsPerLease = -1;   // the record's again
  options.bytesPerWork[0] = options.bytesPerWork[1] = 400;
  options.linkBytesPerSecond = 100e6;
  const ClusterPrediction slowLink = simulateCluster(record, options);
  EXPECT_GT(slowLink.coordinatorUtilization(), 0.9);
  EXPECT_GT(slowLink.seconds(), 3 * recorded.seconds());
  // Every byte crosses the link once: 64 cells x 5 leases x 10 000 work x 400 bytes / 100 MB/s.
  const double linkSeconds = 64 * 5 * 10000 * 400 / 100e6;
  EXPECT_GT(slowLink.seconds(), 0.95 * linkSeconds);
  EXPECT_LT(slowLink.seconds(), 1.3 * linkSeconds);
}

}  // namespace
}  // namespace portico
