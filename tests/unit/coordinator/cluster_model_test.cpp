#include "coordinator/cluster_model.h"

#include <gtest/gtest.h>

namespace portico {
namespace {

// A record of `cells` cells, each with `leasesPerCell` photon leases of
// 10 000 work taking 50 ms each and a render lease of 10 000 taking 20 ms;
// each cell 10 000 triangles loaded in 1 ms.
ClusterRecord uniformRecord(uint32_t cells, int leasesPerCell, double coordinatorSecondsPerLease) {
  ClusterRecord record;
  for (uint32_t c = 0; c < cells; ++c) {
    CellInfo info;
    info.id = c;
    info.triangleCount = 10000;
    info.byteCount = 400000;
    record.cells.push_back(info);
    for (int k = 0; k < leasesPerCell; ++k)
      record.leases.push_back({1, 0, 0, c, 0, 10000, "w", 0, 0, k == 0 ? 51000 : 50000, k == 0 ? 1000 : 0,
                               k == 0 ? 1 : 0, k == 0 ? 10000 : 0});
    record.leases.push_back({1, 0, 1, c, 0, 10000, "w", 0, 0, 21000, 1000, 1, 10000});
  }
  record.coordinatorSecondsPerLease = coordinatorSecondsPerLease;
  return record;
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

}  // namespace
}  // namespace portico
