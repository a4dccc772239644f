// The coordinator's view of a worker: lease sizing and leases in flight.
#include <gtest/gtest.h>

#include "coordinator/worker_registry.h"

namespace portico {
namespace {

TEST(WorkerInfo, TakesASecondLeaseOnlyAfterReadyAndAtMostTwo) {
  WorkerInfo worker;
  EXPECT_FALSE(worker.wantsLease());   // no Ready yet
  worker.ready = true;
  EXPECT_TRUE(worker.wantsLease());
  worker.leases.emplace(1, WorkerInfo::LeaseInFlight{0, 1000});
  EXPECT_TRUE(worker.wantsLease());    // the next one goes out while it traces
  worker.leases.emplace(2, WorkerInfo::LeaseInFlight{0, 1000});
  EXPECT_FALSE(worker.wantsLease());
  worker.leases.erase(1);
  EXPECT_TRUE(worker.wantsLease());
}

// Both leases sent at 0 ms, 1000 rays each; results at 100 and 200 ms. The
// second waited behind the first, so its speed is 1000 rays in 100 ms, not
// in 200 ms: the estimate must not halve because leases queue.
TEST(WorkerInfo, TimesAQueuedLeaseFromThePreviousResult) {
  WorkerInfo worker;
  worker.ready = true;
  worker.leases.emplace(1, WorkerInfo::LeaseInFlight{0, 1000});
  worker.leases.emplace(2, WorkerInfo::LeaseInFlight{0, 1000});
  worker.recordLease(1, 100);
  worker.leases.erase(1);
  EXPECT_DOUBLE_EQ(worker.workPerSecond, 10000.0);
  worker.recordLease(2, 200);
  worker.leases.erase(2);
  EXPECT_DOUBLE_EQ(worker.workPerSecond, 10000.0);
  EXPECT_EQ(worker.nextLeaseWork(50000), 10000);
  // A lease under 20 ms measures the round trip, not the tracing: ignored.
  worker.leases.emplace(3, WorkerInfo::LeaseInFlight{200, 5000});
  worker.recordLease(3, 210);
  EXPECT_DOUBLE_EQ(worker.workPerSecond, 10000.0);
  // An unknown lease (dropped result) changes nothing but the clock.
  worker.recordLease(99, 300);
  EXPECT_DOUBLE_EQ(worker.workPerSecond, 10000.0);
  EXPECT_EQ(worker.lastResultMs, 300);
}

// A photon pass's leases last a few milliseconds: too short to time at the
// coordinator (round trip, queueing), so the worker's own figure is used.
TEST(WorkerInfo, TakesTheWorkersOwnTimeOfAShortLease) {
  WorkerInfo worker;
  worker.ready = true;
  worker.leases.emplace(1, WorkerInfo::LeaseInFlight{0, 6000});
  worker.recordLease(1, 12, /*workerMicros=*/8000);   // 6000 photons in 8 ms
  EXPECT_DOUBLE_EQ(worker.workPerSecond, 750000.0);
  worker.leases.erase(1);
  // Later leases fold in with the same weights as coordinator-timed ones.
  worker.leases.emplace(2, WorkerInfo::LeaseInFlight{20, 3000});
  worker.recordLease(2, 30, 6000);                     // 500 000 per second
  EXPECT_DOUBLE_EQ(worker.workPerSecond, 0.7 * 750000.0 + 0.3 * 500000.0);
  worker.leases.erase(2);
  // Under a millisecond the figure is mostly overhead: timed here instead
  // (and ignored, being under 20 ms here too).
  const double before = worker.workPerSecond;
  worker.leases.emplace(3, WorkerInfo::LeaseInFlight{40, 10});
  worker.recordLease(3, 45, 300);
  EXPECT_DOUBLE_EQ(worker.workPerSecond, before);
}

// At the end of a photon pass leases hold a few photons and are over before
// the next could arrive: a worker is kept up to kMostLeasesInFlight of them
// while they add up to under kQueuedSeconds of its work.
TEST(WorkerInfo, TakesMoreTinyLeasesWhileTheyAddUpToLittleWork) {
  WorkerInfo worker;
  worker.ready = true;
  worker.workPerSecond = 100000;   // kQueuedSeconds of work: 500 rays
  worker.leases.emplace(1, WorkerInfo::LeaseInFlight{0, 300});
  worker.leases.emplace(2, WorkerInfo::LeaseInFlight{0, 150});
  EXPECT_TRUE(worker.wantsLease());    // 450 rays held
  worker.leases.emplace(3, WorkerInfo::LeaseInFlight{0, 60});
  EXPECT_FALSE(worker.wantsLease());   // 510
  worker.leases.erase(3);
  for (uint64_t lease = 10; worker.wantsLease(); ++lease) worker.leases.emplace(lease, WorkerInfo::LeaseInFlight{0, 1});
  EXPECT_EQ(worker.leases.size(), WorkerInfo::kMostLeasesInFlight);
}

}  // namespace
}  // namespace portico
