// Results that do not add up, or hold impossible film values, from real
// worker processes made to send them (PORTICO_TEST_FAULT, worker/test_faults.h):
// each is refused, counted against its worker, and its lease traced again
// by another worker, so the job ends with the bits of a run without them.
// A job fails only when two workers' Results for a cell are refused alike,
// and its error names both.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;

class ResultChecks : public DemoReferenceSuite<ResultChecks> {
 protected:
  static ClusterOptions patientCoordinator() {
    // A cell refused from the faulty worker alone is retried on it until the
    // honest worker joins: more tries than the default three before failing.
    ClusterOptions options;
    options.coordinatorExtra = {"--max-cell-failures", "50"};
    return options;
  }
  // A faulty worker (w0) alone until one of its Results is refused, then an
  // honest one (w1): the job must end done, with the reference's bits.
  static void expectOutvoted(const std::string& fault, const std::string& refusal,
                             const std::vector<std::string>& faultyWorkerExtra = {}) {
    const fs::path dir = dir_ / fault;
    LocalCluster cluster(dir, 0, {}, patientCoordinator());
    const uint64_t job = cluster.submit(store_, dir / "image.exr", kPhotons, 1);
    cluster.addWorker(faultyWorkerExtra, withTestFault(fault));
    ASSERT_TRUE(waitUntil([&] { return readFile(dir / "coordinator.log").find(refusal) != std::string::npos; },
                          std::chrono::seconds(60)))
        << readFile(dir / "coordinator.log");
    cluster.addWorker({});
    const auto status = cluster.wait(job);
    const std::string log = readFile(dir / "coordinator.log");
    ASSERT_EQ(status.value("state", ""), "done") << status.dump(2) << log;
    EXPECT_NE(log.find("from worker w0"), std::string::npos) << log;
    EXPECT_EQ(log.find("from worker w1"), std::string::npos) << log;
    for (const auto& worker : status["workers"])
      if (worker.value("name", "") == "w0")
        EXPECT_GE(worker.value("refused_results", 0), 1) << status.dump(2);
      else
        EXPECT_EQ(worker.value("refused_results", -1), 0) << status.dump(2);
    expectReferenceBits(dir / "image.exr");
  }
  // Two workers with the same fault: the job fails naming both.
  static void expectTwoAgreeingWorkersFailTheJob(const std::string& fault, const std::string& reason) {
    const fs::path dir = dir_ / (fault + "-both");
    LocalCluster cluster(dir, 0);
    const uint64_t job = cluster.submit(store_, dir / "image.exr", kPhotons, 1);
    cluster.addWorker({}, withTestFault(fault));
    cluster.addWorker({}, withTestFault(fault));
    const auto status = cluster.wait(job);
    ASSERT_EQ(status.value("state", ""), "failed") << status.dump(2) << readFile(dir / "coordinator.log");
    const std::string error = status.value("error", "");
    EXPECT_NE(error.find(reason), std::string::npos) << error;
    EXPECT_TRUE(error.find("workers w0 and w1") != std::string::npos ||
                error.find("workers w1 and w0") != std::string::npos)
        << error;
    EXPECT_FALSE(fs::exists(dir / "image.exr"));
  }
};

// Negative film values used to fail the whole job at once, blaming the
// scene's emission. They are one worker's doing: refused, traced again.
TEST_F(ResultChecks, NegativeFilmValuesFromOneWorkerAreRefusedAndTheImageKeepsItsBits) {
  expectOutvoted("negative-film", "film value -");
}

TEST_F(ResultChecks, NegativeFilmValuesFromTwoWorkersFailTheJobNamingBoth) {
  expectTwoAgreeingWorkersFailTheJob("negative-film", "film value -");
}

// Deposit records all zeros (their CRCs right) and no photon counted: the
// Result does not add up to its lease's emission.
TEST_F(ResultChecks, AResultThatEmittedFewerPhotonsThanItsLeaseIsRefused) {
  expectOutvoted("zero-deposits", "photons, its lease asked for");
}

// Rays handed on to other cells dropped, counters honest: its photons do
// not add up.
TEST_F(ResultChecks, AResultWhosePhotonsDoNotAddUpIsRefused) {
  expectOutvoted("drop-crossings", "its photons do not add up");
}

// A render lease's rays handed on twice: more than the portal crossings it
// counted (the worker hands every crossing back: --forward-rays 0).
TEST_F(ResultChecks, ARenderResultHandingOnMoreRaysThanItCountedCrossingsIsRefused) {
  expectOutvoted("duplicate-crossings", "portal crossings", {"--forward-rays", "0"});
}

// A render lease's rays handed on left out, its counters honest: fewer
// rays than crossings is no longer enough, every ray it started must end
// in it or be handed on (before: accepted, and the image lost their light).
TEST_F(ResultChecks, ARenderResultThatLosesTheRaysItHandsOnIsRefused) {
  expectOutvoted("drop-render-crossings", "its rays do not add up", {"--forward-rays", "0"});
}

// Counters that say no shadow, gather or emission ray was traced and none
// finished, the film and crossings intact: the rays do not add up
// (before: accepted, and the job's statistics counted rays never traced).
TEST_F(ResultChecks, ARenderResultWhoseRayCountersDoNotAddUpIsRefused) {
  expectOutvoted("uncounted-rays", "its rays do not add up");
}

TEST_F(ResultChecks, TwoWorkersWhoseResultsDoNotAddUpFailTheJobNamingBoth) {
  expectTwoAgreeingWorkersFailTheJob("zero-deposits", "its lease asked for");
}

}  // namespace
}  // namespace portico
