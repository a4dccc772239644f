// The services' lifecycle as an operator meets it: workers rejoin a
// restarted coordinator within seconds, `portico wait` carries on across the
// restart, tcp://localhost binds, and Ctrl-C stops `portico render` and its
// services within a couple of seconds.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <signal.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <thread>

#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;
using Clock = std::chrono::steady_clock;

class ServiceLifecycle : public DemoStoreSuite<ServiceLifecycle> {};
// Polls until `done` holds; returns how long it took (or `limit`).
std::chrono::milliseconds timeUntil(const std::function<bool()>& done, std::chrono::milliseconds limit) {
  const auto started = Clock::now();
  while (Clock::now() - started < limit) {
    try {
      if (done()) break;
    } catch (const std::exception&) {   // a coordinator not answering yet
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - started);
}

TEST_F(ServiceLifecycle, WorkersRejoinARestartedCoordinatorWithinSeconds) {
  const fs::path dir = dir_ / "rejoin";
  LocalCluster cluster(dir, 0);
  const std::string endpoint = cluster.endpoint();
  // The worker's own defaults: 1 s heartbeats, 10 s before it gives a silent coordinator up.
  ChildProcess worker({kBin + "portico-worker", "--connect", endpoint, "--name", "steady"}, (dir / "worker.log").string());
  const auto joined = [&] { return cluster.status(0)["workers"].size() == 1; };
  ASSERT_LT(timeUntil(joined, std::chrono::seconds(15)), std::chrono::seconds(15)) << readFile(dir / "worker.log");
  cluster.killCoordinator();
  cluster.startCoordinator(endpoint);
  const auto rejoined = timeUntil(joined, std::chrono::seconds(20));
  RecordProperty("rejoin_ms", int(rejoined.count()));
  EXPECT_LT(rejoined, std::chrono::seconds(4)) << readFile(dir / "worker.log");
  EXPECT_NE(readFile(dir / "worker.log").find("restarted: joining it again"), std::string::npos)
      << readFile(dir / "worker.log");
}

TEST_F(ServiceLifecycle, WaitCarriesOnAcrossACoordinatorRestartAndExitsZero) {
  const fs::path dir = dir_ / "wait";
  LocalCluster cluster(dir, 0);   // no worker: the job waits
  const std::string endpoint = cluster.endpoint();
  const uint64_t job = cluster.submit(store_, dir / "image.exr", 5000, 1);
  ChildProcess wait({kBin + "portico", "wait", "--coordinator", endpoint, std::to_string(job), "--quiet"},
                    (dir / "wait.log").string());
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  // Stopped, the coordinator takes the next request and never answers it; killed, it loses it.
  cluster.pauseCoordinator();
  std::this_thread::sleep_for(std::chrono::milliseconds(600));
  cluster.killCoordinator();
  cluster.startCoordinator(endpoint);
  cluster.addWorker({});
  const auto took = timeUntil([&] { return !wait.running(); }, std::chrono::seconds(60));
  EXPECT_LT(took, std::chrono::seconds(25)) << readFile(dir / "wait.log");
  EXPECT_EQ(wait.wait(), 0) << readFile(dir / "wait.log");
  EXPECT_TRUE(fs::exists(dir / "image.exr"));
}

TEST_F(ServiceLifecycle, TcpLocalhostIsBoundAsLoopback) {
  const fs::path dir = dir_ / "localhost";
  ClusterOptions options;
  options.listen = "tcp://localhost:*";
  LocalCluster cluster(dir, 1, {}, options);
  EXPECT_EQ(cluster.endpoint().rfind("tcp://127.0.0.1:", 0), 0u) << cluster.endpoint();
  const auto status = cluster.render(store_, dir / "image.exr", 2000, 1);
  EXPECT_EQ(status.value("state", ""), "done") << status.dump(2);
}

// The processes whose parent is `parent`.
std::vector<pid_t> childrenOf(pid_t parent) {
  std::vector<pid_t> children;
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream stat(entry.path() / "stat");
    std::string line;
    std::getline(stat, line);
    const size_t close = line.rfind(')');
    if (close == std::string::npos) continue;
    std::istringstream rest(line.substr(close + 2));
    char state;
    pid_t ppid = 0;
    rest >> state >> ppid;
    if (ppid == parent) children.push_back(pid_t(std::stoi(name)));
  }
  return children;
}

TEST_F(ServiceLifecycle, CtrlCStopsPorticoRenderAndItsServicesWithinTwoSeconds) {
  const fs::path dir = dir_ / "ctrl-c";
  fs::create_directories(dir);
  ChildProcess render({kBin + "portico", "render", store_.string(), "-o", (dir / "image.exr").string(), "--workers", "2",
                       "--photons", "50000000", "--width", "96", "--height", "64"},
                      (dir / "render.log").string());
  // Under way: the coordinator and both workers started, the photon pass begun.
  std::vector<pid_t> services;
  timeUntil([&] { return (services = childrenOf(render.pid())).size() == 3; }, std::chrono::seconds(20));
  ASSERT_EQ(services.size(), 3u) << readFile(dir / "render.log");
  std::this_thread::sleep_for(std::chrono::seconds(2));
  ASSERT_TRUE(render.running()) << readFile(dir / "render.log");
  // A terminal's Ctrl-C: SIGINT to the whole foreground process group.
  render.kill(SIGINT);
  for (pid_t service : services) ::kill(service, SIGINT);
  const auto took = timeUntil([&] { return !render.running(); }, std::chrono::seconds(60));
  RecordProperty("ctrl_c_ms", int(took.count()));
  EXPECT_LT(took, std::chrono::milliseconds(2500)) << readFile(dir / "render.log");
  EXPECT_EQ(render.exitCode(), 1);
  for (pid_t service : services) EXPECT_FALSE(fs::exists("/proc/" + std::to_string(service))) << service;
}

}  // namespace
}  // namespace portico
