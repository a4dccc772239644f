// The coordinator's own bound on a lease (--lease-timeout-s): a worker
// whose heartbeats go on while its tracing thread is stuck (a read that
// never returns) has its leases taken back after that long without
// progress, and they are traced elsewhere with the same bits; its late
// Result, if one still comes, is dropped; cancel frees its leases and
// SIGTERM ends it within a bounded time. Real worker processes made to
// block inside a lease by the test hook PORTICO_TEST_FAULT
// (worker/test_faults.h).
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <csignal>
#include <string>
#include <vector>

#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;
using Clock = std::chrono::steady_clock;

class LeaseBound : public DemoReferenceSuite<LeaseBound> {
 protected:
  static ClusterOptions leaseTimeout(const std::string& seconds) {
    ClusterOptions options;
    options.coordinatorExtra = {"--lease-timeout-s", seconds};
    return options;
  }
  static const nlohmann::json* workerNamed(const nlohmann::json& status, const std::string& name) {
    for (const auto& worker : status["workers"])
      if (worker.value("name", "") == name) return &worker;
    return nullptr;
  }
  static int64_t leasesOf(LocalCluster& cluster, uint64_t job, const std::string& name) {
    const auto status = cluster.status(job);
    const nlohmann::json* worker = workerNamed(status, name);
    return worker ? worker->value("leases", int64_t{0}) : 0;
  }
  static std::string waitingReasons(const nlohmann::json& status) {
    std::string text;
    if (status.contains("waiting"))
      for (const auto& reason : status["waiting"]) text += reason.get<std::string>() + "\n";
    return text;
  }
  // Submits a job and starts w0 stuck for good in its first lease; returns
  // the job once w0 is seen holding a lease of it (0: it never was).
  static uint64_t submitToAStuckWorker(LocalCluster& cluster, const fs::path& dir) {
    const uint64_t job = cluster.submit(store_, dir / "image.exr", kPhotons, 1);
    cluster.addWorker({}, withTestFault("hang-in-lease"));
    return waitUntil([&] { return leasesOf(cluster, job, "w0") > 0; }, std::chrono::seconds(30)) ? job : 0;
  }
  // The job ends done with the reference's bits.
  static void expectDoneWithReferenceBits(const nlohmann::json& status, const fs::path& dir) {
    ASSERT_EQ(status.value("state", ""), "done") << status.dump(2) << readFile(dir / "coordinator.log");
    expectReferenceBits(dir / "image.exr");
  }
};

// A worker blocked for good inside its first lease, its heartbeats going
// on: its leases are taken back 2 s after it last moved, status says so,
// another worker finishes the job with the bits of a clean run, and the
// stuck worker stops within seconds of SIGTERM. Before the bound, the job
// waited for good.
TEST_F(LeaseBound, AWorkerStuckInALeaseHasItTakenBackAndAnotherWorkerFinishesWithTheSameBits) {
  const fs::path dir = dir_ / "stuck";
  LocalCluster cluster(dir, 0, {}, leaseTimeout("2"));
  const uint64_t job = submitToAStuckWorker(cluster, dir);
  ASSERT_NE(job, 0u) << readFile(dir / "coordinator.log");
  const auto leased = Clock::now();
  nlohmann::json status;
  ASSERT_TRUE(waitUntil(
      [&] {
        status = cluster.status(job);
        return waitingReasons(status).find("taken back from worker w0") != std::string::npos;
      },
      std::chrono::seconds(20)))
      << status.dump(2) << readFile(dir / "coordinator.log");
  const double takenBackS = std::chrono::duration<double>(Clock::now() - leased).count();
  std::printf("lease of the stuck worker taken back %.2f s after it was seen leased (--lease-timeout-s 2)\n",
              takenBackS);
  EXPECT_LT(takenBackS, 4.0);
  EXPECT_NE(waitingReasons(status).find("no progress for"), std::string::npos) << status.dump(2);
  const nlohmann::json* stuck = workerNamed(status, "w0");
  ASSERT_NE(stuck, nullptr) << status.dump(2);
  EXPECT_EQ(stuck->value("leases", int64_t{-1}), 0) << status.dump(2);
  EXPECT_NE(stuck->value("stalled", "").find("no progress for"), std::string::npos) << status.dump(2);
  // What `portico status` prints says it too.
  int code = 0;
  const std::string printed = captureOutput(
      {kBin + "portico", "status", "--coordinator", cluster.endpoint(), std::to_string(job)}, dir, "status", &code);
  EXPECT_EQ(code, 0);
  EXPECT_NE(printed.find("waiting: cell"), std::string::npos) << printed;
  EXPECT_NE(printed.find("taken back from worker w0"), std::string::npos) << printed;
  EXPECT_NE(printed.find("w0 stalled"), std::string::npos) << printed;
  std::printf("%s", waitingReasons(status).c_str());

  cluster.addWorker({});
  expectDoneWithReferenceBits(cluster.wait(job), dir);
  EXPECT_NE(readFile(dir / "worker-0.log").find("hang-in-lease"), std::string::npos);
  ASSERT_TRUE(cluster.worker(0).running()) << "the stuck worker should still be there, stuck";

  const double stopS = secondsToExitOnSigterm(cluster.worker(0), std::chrono::seconds(20));
  std::printf("the stuck worker exited %.2f s after SIGTERM\n", stopS);
  EXPECT_GE(stopS, 0) << readFile(dir / "worker-0.log");
  EXPECT_LT(stopS, 12.0);
}

// A worker that stops moving for 4 s in its first lease, then goes on: the
// lease is taken back after 1.5 s and traced by another worker; the late
// Result that comes after is dropped (its lease is no longer the worker's),
// its deposits in the photon file are never read, the worker takes leases
// again, and the image keeps the clean run's bits.
TEST_F(LeaseBound, TheLateResultOfATakenBackLeaseIsDroppedAndTheImageKeepsItsBits) {
  const fs::path dir = dir_ / "late";
  LocalCluster cluster(dir, 0, {}, leaseTimeout("1.5"));
  const uint64_t job = cluster.submit(store_, dir / "image.exr", kPhotons, 1);
  cluster.addWorker({}, withTestFault("stall-in-lease"));
  ASSERT_TRUE(waitUntil([&] { return readFile(dir / "coordinator.log").find("taken back") != std::string::npos; },
                        std::chrono::seconds(30)))
      << readFile(dir / "coordinator.log");
  cluster.addWorker({});
  expectDoneWithReferenceBits(cluster.wait(job), dir);
  ASSERT_TRUE(waitUntil(
      [&] { return readFile(dir / "coordinator.log").find("moves again") != std::string::npos; },
      std::chrono::seconds(15)))
      << readFile(dir / "coordinator.log");
  const std::string log = readFile(dir / "coordinator.log");
  EXPECT_NE(log.find("dropped a result for lease"), std::string::npos) << log;
}

// A worker whose tracing thread computes for 4 s without counting anything
// (a long accelerator or photon map build) is moving: its CPU time counts as
// progress, so a 1.5 s bound does not take its lease back, and it finishes
// the job alone with the clean run's bits.
TEST_F(LeaseBound, ALeaseThatComputesLongerThanTheBoundIsNotTakenBack) {
  const fs::path dir = dir_ / "busy";
  LocalCluster cluster(dir, 0, {}, leaseTimeout("1.5"));
  const uint64_t job = cluster.submit(store_, dir / "image.exr", kPhotons, 1);
  cluster.addWorker({}, withTestFault("busy-in-lease"));
  expectDoneWithReferenceBits(cluster.wait(job), dir);
  const std::string log = readFile(dir / "coordinator.log");
  EXPECT_EQ(log.find("taken back"), std::string::npos) << log;
  const std::string workerLog = readFile(dir / "worker-0.log");
  EXPECT_NE(workerLog.find("busy-in-lease"), std::string::npos) << "the fault never ran: " << workerLog;
}

// Cancel frees the leases of a worker whose tracing thread is stuck at once
// (no waiting out the bound), and SIGTERM ends that worker.
TEST_F(LeaseBound, CancelFreesTheLeasesOfAStuckWorkerAndSigtermEndsIt) {
  const fs::path dir = dir_ / "cancel";
  LocalCluster cluster(dir, 0, {}, leaseTimeout("600"));
  const uint64_t job = submitToAStuckWorker(cluster, dir);
  ASSERT_NE(job, 0u) << readFile(dir / "coordinator.log");
  net::CoordinatorClient client(cluster.endpoint());
  const auto cancelled = nlohmann::json::parse(client.cancel(job));
  EXPECT_EQ(cancelled.value("state", ""), "cancelled") << cancelled.dump(2);
  const nlohmann::json* stuck = workerNamed(cancelled, "w0");
  ASSERT_NE(stuck, nullptr) << cancelled.dump(2);
  EXPECT_EQ(stuck->value("leases", int64_t{-1}), 0) << cancelled.dump(2);

  const double stopS = secondsToExitOnSigterm(cluster.worker(0), std::chrono::seconds(20));
  std::printf("the stuck worker exited %.2f s after SIGTERM\n", stopS);
  EXPECT_GE(stopS, 0) << readFile(dir / "worker-0.log");
  EXPECT_LT(stopS, 12.0);
  EXPECT_NE(readFile(dir / "worker-0.log").find("did not stop within"), std::string::npos)
      << readFile(dir / "worker-0.log");
}

}  // namespace
}  // namespace portico
