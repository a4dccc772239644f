// Helpers of the integration tests that start the real services: temporary
// directories, commands run to a log, and a coordinator with N workers
// started by hand, as a user would.
#pragma once

#include <capnp/message.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <fstream>
#include <csignal>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>

#include "common/image/image_reader.h"
#include "common/net/client.h"
#include "common/net/curve_keys.h"
#include "common/util/child_process.h"
#include "tests/support/temp_directory.h"

namespace portico::harness {

namespace fs = std::filesystem;
// The programs under test: this build's, or PORTICO_TEST_BIN's (e.g. another
// checkout's build/bin/, to see a test fail on the code it guards against).
inline const std::string kBin =
    std::getenv("PORTICO_TEST_BIN") ? std::string(std::getenv("PORTICO_TEST_BIN")) + "/"
                                    : std::string(PORTICO_BINARY_DIR) + "/bin/";

// Removed when the test program ends with every test passed.
inline fs::path makeTempDirectory(const std::string& name) { return testing_support::tempPath("test-" + name); }

inline int runCommand(const std::vector<std::string>& argv, const fs::path& log) {
  ChildProcess process(argv, log.string());
  return process.wait();
}

inline std::string readFile(const fs::path& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Runs a command and returns its standard output (stderr goes to the log).
inline std::string captureOutput(const std::vector<std::string>& argv, const fs::path& dir, const std::string& name,
                                 int* exitCode) {
  const fs::path out = dir / (name + ".out");
  std::vector<std::string> shell{"/bin/sh", "-c", ""};
  std::string command;
  for (const std::string& a : argv) command += "'" + a + "' ";
  shell[2] = command + "> '" + out.string() + "'";
  *exitCode = runCommand(shell, dir / (name + ".log"));
  return readFile(out);
}

// Polls until `condition` holds or `limit` passes; returns whether it held.
inline bool waitUntil(const std::function<bool()>& condition, std::chrono::milliseconds limit) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (!condition()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return true;
}

// Every photon emitted is absorbed or escapes; nothing left queued.
inline void expectConservation(const nlohmann::json& stats) {
  const auto& photons = stats["photons"];
  EXPECT_GT(photons["emitted"].get<int64_t>(), 0);
  EXPECT_EQ(photons["emitted"].get<int64_t>(),
            photons["absorbed"].get<int64_t>() + photons["escaped"].get<int64_t>());
  EXPECT_EQ(photons["queued"].get<int64_t>(), 0);
  EXPECT_GT(photons["deposits"].get<int64_t>(), photons["emitted"].get<int64_t>() / 2);
  EXPECT_EQ(stats["rays"]["queued"].get<int64_t>(), 0);
  EXPECT_EQ(stats["rays"]["invalid"].get<int64_t>(), 0);
  // Every shadow ray ends exactly once: blocked, reached, or escaped.
  EXPECT_GE(stats["rays"]["shadow"].get<int64_t>(),
            stats["rays"]["shadow_blocked"].get<int64_t>() + stats["rays"]["shadow_reached"].get<int64_t>());
}

// Reads an EXR and counts the floats whose bits differ from another.
inline size_t differingFloats(const fs::path& a, const fs::path& b) {
  const LinearImage x = readImage(a.string()), y = readImage(b.string());
  if (x.rgb.size() != y.rgb.size()) return SIZE_MAX;
  size_t differing = 0;
  for (size_t i = 0; i < x.rgb.size(); ++i) differing += std::memcmp(&x.rgb[i], &y.rgb[i], sizeof(float)) != 0;
  return differing;
}

// Writes the demo building into `store` (`portico scene generate`); returns
// "" on success, else the command's log, for the assertion's message.
inline std::string generateDemoStore(const fs::path& store, int seed) {
  const fs::path log = store.string() + ".generate.log";
  const int code = runCommand(
      {kBin + "portico", "scene", "generate", "--preset", "demo", "--seed", std::to_string(seed), store.string()}, log);
  return code == 0 ? std::string() : "portico scene generate failed: " + readFile(log);
}

// Imports tests/scenes/NAME/scene.json into `store`, its meshes cut into
// voxel cells of a grid x grid x grid lattice (`portico scene import
// --grid`); returns "" on success, else the command's log.
// A test suite whose tests share one demo building, generated once into a
// temporary directory named after the suite (`Suite`: the derived fixture,
// so that each suite has its own directory and store).
template <class Suite>
class DemoStoreSuite : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = makeTempDirectory(::testing::UnitTest::GetInstance()->current_test_suite()->name());
    store_ = dir_ / "demo";
    ASSERT_EQ(generateDemoStore(store_, 3), "");
  }
  static inline fs::path dir_, store_;
};

// The worker's command line run with PORTICO_TEST_FAULT=fault: a test hook
// that makes it misbehave on purpose (worker/test_faults.h).
inline std::function<std::vector<std::string>(std::vector<std::string>)> withTestFault(const std::string& fault) {
  return [fault](std::vector<std::string> argv) {
    argv.insert(argv.begin(), {"/usr/bin/env", "PORTICO_TEST_FAULT=" + fault});
    return argv;
  };
}

inline std::string importVoxelStore(const std::string& name, int grid, const fs::path& store) {
  const fs::path log = store.string() + ".import.log";
  const int code = runCommand({kBin + "portico", "scene", "import", "--grid", std::to_string(grid),
                               std::string(PORTICO_SOURCE_DIR) + "/tests/scenes/" + name + "/scene.json", store.string()},
                              log);
  return code == 0 ? std::string() : "portico scene import failed: " + readFile(log);
}

// Gives a hand-made socket the keys this user's programs present to a
// coordinator started without --keys (the per-user keys on tcp://; none on
// ipc://), in `role`: tests that speak the protocol themselves.
inline void useLocalKeys(zmq::socket_t& socket, const std::string& endpoint, net::Role role) {
  if (const std::string keys = net::keysForEndpoint("", endpoint); !keys.empty())
    net::applyClientKeys(socket, net::loadClientKeys(keys, role));
}

// How a LocalCluster's services are started beyond the defaults.
struct ClusterOptions {
  std::string listen = "tcp://127.0.0.1:*";
  std::vector<std::string> coordinatorExtra;   // e.g. {"--keys", DIR}
  std::vector<std::string> coordinatorPrefix;  // a command that runs it, e.g. {"prlimit", "--nofile=256:256", "--"}
  std::string clientKeys;                      // the tests' own client: CURVE keys directory
};

// A coordinator and N workers started by hand, as a user would.
class LocalCluster {
 public:
  // workerExtra[i] are extra arguments of worker i (fault injection, keys).
  LocalCluster(const fs::path& dir, int workers, const std::vector<std::vector<std::string>>& workerExtra = {},
               ClusterOptions options = {})
      : dir_(dir), options_(std::move(options)) {
    fs::create_directories(dir);
    startCoordinator(options_.listen);
    for (int i = 0; i < workers; ++i) addWorker(size_t(i) < workerExtra.size() ? workerExtra[i] : std::vector<std::string>{});
  }
  ~LocalCluster() {
    for (auto& w : workers_) w.stop();
    coordinator_->stop();
  }
  const std::string& endpoint() const { return endpoint_; }

  // Starts one more worker (named w<index>, logging to worker-<index>.log).
  // `wrap` turns the worker's command line into the one to run (e.g. inside
  // a mount namespace that hides the scene store).
  void addWorker(const std::vector<std::string>& extra,
                 const std::function<std::vector<std::string>(std::vector<std::string>)>& wrap = nullptr) {
    const std::string index = std::to_string(workers_.size());
    std::vector<std::string> argv{kBin + "portico-worker", "--connect", endpoint_, "--name", "w" + index,
                                  "--heartbeat-ms", "250", "--liveness-ms", "1500"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    workers_.emplace_back(wrap ? wrap(argv) : argv, (dir_ / ("worker-" + index + ".log")).string());
  }
  ChildProcess& worker(size_t i) { return workers_.at(i); }
  ChildProcess& coordinator() { return *coordinator_; }

  // (Re)starts the coordinator on `listen` with the cluster's jobs.db.
  void startCoordinator(const std::string& listen) {
    fs::remove(dir_ / "endpoint");
    std::vector<std::string> argv{kBin + "portico-coordinator", "--listen", listen, "--db", (dir_ / "jobs.db").string(),
                                  "--endpoint-file", (dir_ / "endpoint").string(), "--liveness-ms", "2000",
                                  "--heartbeat-ms", "250"};
    argv.insert(argv.end(), options_.coordinatorExtra.begin(), options_.coordinatorExtra.end());
    argv.insert(argv.begin(), options_.coordinatorPrefix.begin(), options_.coordinatorPrefix.end());
    coordinator_ = std::make_unique<ChildProcess>(argv, (dir_ / "coordinator.log").string());
    endpoint_.clear();
    for (int i = 0; i < 400 && endpoint_.empty(); ++i) {
      std::ifstream in(dir_ / "endpoint");
      in >> endpoint_;
      if (endpoint_.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(25));
    }
    if (endpoint_.empty()) throw std::runtime_error("coordinator did not start: " + readFile(dir_ / "coordinator.log"));
  }
  // SIGSTOP: it accepts requests and answers none (until killed).
  void pauseCoordinator() { coordinator_->kill(SIGSTOP); }
  // kill -9: no chance to write anything down.
  void killCoordinator() {
    coordinator_->kill(SIGKILL);
    coordinator_->wait();
  }

  // `adjust` changes the test spec before it is sent (more gather rays, ...).
  uint64_t submit(const fs::path& store, const fs::path& output, uint64_t photons, uint32_t spp,
                  const std::function<void(wire::JobSpec::Builder)>& adjust = nullptr) {
    net::CoordinatorClient client(endpoint_, options_.clientKeys);
    capnp::MallocMessageBuilder message;
    auto spec = message.initRoot<wire::Envelope>().initSubmit().initSpec();
    spec.setStore(store.string());
    spec.setOutput(output.string());
    spec.setAccel("grid");
    spec.setPhotons(photons);
    spec.setSpp(spp);
    spec.setSeed(7);
    spec.setWidth(96);
    spec.setHeight(64);
    spec.setLightSamples(1);
    spec.setPhotonK(32);
    spec.setPhotonRadius(0.5f);
    spec.setExposure(1);
    spec.setGather(2);   // final gathering: gather rays cross portals too
    if (adjust) adjust(spec);
    return client.submit(message);
  }

  nlohmann::json status(uint64_t job) {
    net::CoordinatorClient client(endpoint_, options_.clientKeys);
    return nlohmann::json::parse(client.statusJson(job));
  }

  nlohmann::json wait(uint64_t job) {
    for (int i = 0; i < 1200; ++i) {
      auto current = status(job);
      const std::string state = current.value("state", "");
      if (state != "photons" && state != "render") return current;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    throw std::runtime_error("job did not finish within 120 s");
  }

  // Submits and waits; returns the final status.
  nlohmann::json render(const fs::path& store, const fs::path& output, uint64_t photons, uint32_t spp) {
    return wait(submit(store, output, photons, spp));
  }

 private:
  fs::path dir_;
  ClusterOptions options_;
  std::unique_ptr<ChildProcess> coordinator_;
  std::vector<ChildProcess> workers_;
  std::string endpoint_;
};

// SIGTERM, then waits up to `limit` for the process to exit: the seconds it
// took, or -1 if it is still running.
inline double secondsToExitOnSigterm(ChildProcess& process, std::chrono::seconds limit) {
  const auto sent = std::chrono::steady_clock::now();
  process.kill(SIGTERM);
  if (!waitUntil([&] { return !process.running(); }, limit)) return -1;
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - sent).count();
}

// A DemoStoreSuite with a clean run of its building (kPhotons photons, 1
// spp, one worker) in reference.exr and its .json: the bits that runs with
// misbehaving workers must keep.
template <class Suite>
class DemoReferenceSuite : public DemoStoreSuite<Suite> {
 protected:
  using Base = DemoStoreSuite<Suite>;
  static constexpr uint64_t kPhotons = 30000;
  static void SetUpTestSuite() {
    Base::SetUpTestSuite();
    if (::testing::Test::HasFatalFailure()) return;
    LocalCluster cluster(Base::dir_ / "reference", 1);
    const auto status = cluster.render(Base::store_, Base::dir_ / "reference.exr", kPhotons, 1);
    ASSERT_EQ(status.value("state", ""), "done") << status.dump(2);
  }
  // `image` (and its .json) has the reference's bits and photons, every photon accounted for.
  static void expectReferenceBits(const fs::path& image) {
    const auto stats = nlohmann::json::parse(readFile(image.string() + ".json"));
    expectConservation(stats);
    EXPECT_EQ(stats["photons"], nlohmann::json::parse(readFile(Base::dir_ / "reference.exr.json"))["photons"]);
    EXPECT_EQ(differingFloats(image, Base::dir_ / "reference.exr"), 0u);
  }
};

}  // namespace portico::harness
