// Stopping work that is under way, through real processes: a cancelled
// job's running lease stops within about a second (the coordinator tells
// its worker, which checks between small pieces of work), and SIGTERM stops
// a worker in the middle of a long lease, and the coordinator, promptly.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <csignal>
#include <thread>

#include "common/net/client.h"
#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;

class Interruption : public DemoStoreSuite<Interruption> {
 protected:
  // A job whose render leases last tens of seconds (64 spp, 1024 gather rays
  // per camera hit: a camera batch is 16 M gather rays); returns once a
  // worker has traced one render lease for half a second (0: never got there).
  static uint64_t submitLongRender(LocalCluster& cluster, const fs::path& dir) {
    const uint64_t job = cluster.submit(store_, dir / "image.exr", 2000, 64, [](wire::JobSpec::Builder spec) {
      spec.setGather(1024);
    });
    const bool rendering = waitUntil(
        [&] {
          const auto status = cluster.status(job);
          return status.value("state", "") == "render" && !status["workers"].empty() &&
                 status["workers"][0].value("leases", 0) > 0;
        },
        std::chrono::seconds(60));
    if (!rendering) return 0;
    // The render's first leases can be short (the emitted light's camera
    // rays, cells few pixels see): wait until one has run half a second,
    // i.e. no lease has come back for that long while the worker holds one.
    int64_t completed = -1;
    auto since = std::chrono::steady_clock::now();
    const bool longLease = waitUntil(
        [&] {
          const auto status = cluster.status(job);
          const int64_t now = status.value("leases", int64_t(0));
          const auto t = std::chrono::steady_clock::now();
          if (now != completed || status["workers"].empty() || status["workers"][0].value("leases", 0) == 0) {
            completed = now;
            since = t;
          }
          return t - since >= std::chrono::milliseconds(500);
        },
        std::chrono::seconds(60));
    return longLease ? job : 0;
  }
};

// Without the Cancel to its worker, `portico cancel` would mark the job
// cancelled while the worker traced on for as long as the lease lasted.
TEST_F(Interruption, CancellingAJobStopsItsRunningLeaseWithinASecond) {
  const fs::path dir = dir_ / "cancel";
  LocalCluster cluster(dir, 1);
  const uint64_t job = submitLongRender(cluster, dir);
  ASSERT_NE(job, 0u) << readFile(dir / "coordinator.log");
  const auto cancelled = std::chrono::steady_clock::now();
  net::CoordinatorClient(cluster.endpoint()).cancel(job);
  const bool stopped = waitUntil([&] { return readFile(dir / "worker-0.log").find("stopped midway") != std::string::npos; },
                                 std::chrono::seconds(3));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - cancelled).count();
  ASSERT_TRUE(stopped) << readFile(dir / "worker-0.log");
  std::cout << "the running lease stopped " << seconds << " s after the cancel\n";
  EXPECT_LT(seconds, 1.5);
  EXPECT_EQ(cluster.status(job).value("state", ""), "cancelled");
  // The worker is free again: a new job runs to the end.
  const auto status = cluster.render(store_, dir / "after.exr", 2000, 1);
  EXPECT_EQ(status.value("state", ""), "done") << status.dump(2);
}

// SIGTERM to a worker deep in a long lease, then to the coordinator: each
// exits cleanly (status 0) within about a second, not when the lease ends.
TEST_F(Interruption, SigtermStopsATracingWorkerAndTheCoordinatorPromptly) {
  const fs::path dir = dir_ / "sigterm";
  LocalCluster cluster(dir, 1);
  ASSERT_NE(submitLongRender(cluster, dir), 0u) << readFile(dir / "coordinator.log");
  for (ChildProcess* process : {&cluster.worker(0), &cluster.coordinator()}) {
    const auto signalled = std::chrono::steady_clock::now();
    process->kill(SIGTERM);
    const bool exited = waitUntil([&] { return !process->running(); }, std::chrono::seconds(3));
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - signalled).count();
    ASSERT_TRUE(exited) << readFile(dir / "worker-0.log");
    std::cout << "exited " << seconds << " s after SIGTERM\n";
    EXPECT_LT(seconds, 1.5);
    EXPECT_EQ(process->exitCode(), 0);
  }
}

// `portico render` interrupted in a long render pass: it cancels the job,
// stops its workers and its coordinator, and exits (status 1, the job not
// done) within a couple of seconds, leaving no process behind.
TEST_F(Interruption, SigtermStopsPorticoRenderPromptly) {
  const fs::path dir = dir_ / "render";
  fs::create_directories(dir);
  ChildProcess render({kBin + "portico", "render", store_.string(), "-o", (dir / "image.exr").string(), "--workers",
                       "1", "--photons", "2000", "--spp", "64", "--gather", "1024", "--width", "96", "--height", "64"},
                      (dir / "render.log").string());
  // Its photon pass takes well under these seconds; its render pass, minutes.
  std::this_thread::sleep_for(std::chrono::seconds(4));
  ASSERT_TRUE(render.running()) << readFile(dir / "render.log");
  const auto signalled = std::chrono::steady_clock::now();
  render.kill(SIGTERM);
  const bool exited = waitUntil([&] { return !render.running(); }, std::chrono::seconds(10));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - signalled).count();
  ASSERT_TRUE(exited) << readFile(dir / "render.log");
  std::cout << "portico render exited " << seconds << " s after SIGTERM\n";
  EXPECT_LT(seconds, 2.5) << readFile(dir / "render.log");
  EXPECT_EQ(render.exitCode(), 1);
  EXPECT_NE(readFile(dir / "render.log").find("interrupted"), std::string::npos) << readFile(dir / "render.log");
}

}  // namespace
}  // namespace portico
