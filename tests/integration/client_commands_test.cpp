// What the `portico` client commands report, with a real coordinator and
// workers: `portico wait` gives a finished job's own time, `portico
// shutdown` fails when the coordinator did not stop, a coordinator on
// tcp://[::1] serves, and bad values (a worker's --memory, a number beyond
// a double in building.json) are refused at once, naming what is wrong.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <fstream>
#include <regex>
#include <thread>

#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;

class ClientCommands : public DemoStoreSuite<ClientCommands> {};

// A job's time is from its submit to its end: asked later, it does not grow.
TEST_F(ClientCommands, WaitGivesAFinishedJobsOwnTime) {
  const fs::path dir = dir_ / "wait";
  LocalCluster cluster(dir, 1);
  const auto done = cluster.render(store_, dir / "image.exr", 20000, 1);
  ASSERT_EQ(done.value("state", ""), "done") << done.dump(2);
  const uint64_t job = done.value("job", uint64_t{0});
  const double jobSeconds = done.value("elapsed_s", 0.0);
  std::this_thread::sleep_for(std::chrono::milliseconds(2500));
  EXPECT_EQ(cluster.status(job).value("elapsed_s", -1.0), jobSeconds);
  int code = -1;
  captureOutput({kBin + "portico", "wait", "--coordinator", cluster.endpoint(), std::to_string(job)}, dir, "wait", &code);
  EXPECT_EQ(code, 0) << readFile(dir / "wait.log");
  std::smatch said;
  const std::string log = readFile(dir / "wait.log");
  ASSERT_TRUE(std::regex_search(log, said, std::regex("done in ([0-9.]+) s"))) << log;
  EXPECT_LE(std::stod(said[1]), jobSeconds + 0.05) << log;
}

// A shutdown nobody answered (here: keys the coordinator does not know)
// did not happen: the command says so and fails; an operator's succeeds.
TEST_F(ClientCommands, ShutdownFailsUnlessTheCoordinatorStops) {
  const fs::path dir = dir_ / "shutdown";
  const fs::path keys = dir / "keys", other = dir / "other";
  fs::create_directories(dir);
  ASSERT_EQ(runCommand({kBin + "portico", "keys", "generate", keys.string()}, dir / "keys.log"), 0);
  ASSERT_EQ(runCommand({kBin + "portico", "keys", "generate", other.string()}, dir / "keys.log"), 0);
  ClusterOptions options;
  options.coordinatorExtra = {"--keys", keys.string()};
  options.clientKeys = keys.string();
  LocalCluster cluster(dir, 0, {}, options);
  int code = -1;
  const std::string refused = captureOutput({kBin + "portico", "shutdown", "--coordinator", cluster.endpoint(),
                                             "--keys", other.string(), "--timeout", "2"},
                                            dir, "refused", &code);
  EXPECT_NE(code, 0) << refused << readFile(dir / "refused.log");
  EXPECT_EQ(refused.find("stopping"), std::string::npos) << refused;
  EXPECT_EQ(refused.find("sent"), std::string::npos) << refused;
  EXPECT_NE(readFile(dir / "refused.log").find("no answer"), std::string::npos) << readFile(dir / "refused.log");
  EXPECT_NO_THROW(cluster.status(0));   // still serving

  const std::string stopped = captureOutput(
      {kBin + "portico", "shutdown", "--coordinator", cluster.endpoint(), "--keys", keys.string(), "--timeout", "10"},
      dir, "stopped", &code);
  EXPECT_EQ(code, 0) << readFile(dir / "stopped.log");
  EXPECT_NE(stopped.find("is stopping"), std::string::npos) << stopped;
  EXPECT_TRUE(waitUntil([&] { return !cluster.coordinator().running(); }, std::chrono::seconds(10)));
}

bool ipv6LoopbackWorks() {
  const int fd = ::socket(AF_INET6, SOCK_STREAM, 0);
  if (fd < 0) return false;
  sockaddr_in6 address{};
  address.sin6_family = AF_INET6;
  address.sin6_addr = in6addr_loopback;
  const bool bound = ::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0;
  ::close(fd);
  return bound;
}

// Documented as allowed without keys; it used to fail with "No such device".
TEST_F(ClientCommands, ACoordinatorOnIpv6LoopbackServesWorkersAndClients) {
  if (!ipv6LoopbackWorks()) GTEST_SKIP() << "no IPv6 loopback on this machine";
  const fs::path dir = dir_ / "ipv6";
  ClusterOptions options;
  options.listen = "tcp://[::1]:*";
  LocalCluster cluster(dir, 1, {}, options);
  EXPECT_EQ(cluster.endpoint().rfind("tcp://[::1]:", 0), 0u) << cluster.endpoint();
  const auto status = cluster.render(store_, dir / "image.png", 5000, 1);
  EXPECT_EQ(status.value("state", ""), "done") << status.dump(2) << readFile(dir / "coordinator.log");
  int code = -1;
  const std::string text = captureOutput(
      {kBin + "portico", "status", "--coordinator", cluster.endpoint(), "--timeout", "10"}, dir, "status", &code);
  EXPECT_EQ(code, 0) << readFile(dir / "status.log");
  EXPECT_NE(text.find("done"), std::string::npos) << text;
}

// A budget no worker can start with is refused on the command line, by
// `portico render` (before it starts any worker) and by the worker.
TEST_F(ClientCommands, AMemoryBudgetNoWorkerCanStartWithIsRefusedAtOnce) {
  const fs::path dir = dir_ / "memory";
  fs::create_directories(dir);
  const auto started = std::chrono::steady_clock::now();
  EXPECT_NE(runCommand({kBin + "portico", "render", store_.string(), "-o", (dir / "x.png").string(), "--memory", "1B"},
                       dir / "render.log"),
            0);
  EXPECT_NE(runCommand({kBin + "portico-worker", "--connect", "tcp://127.0.0.1:1", "--memory", "1B"}, dir / "worker.log"),
            0);
  EXPECT_LT(std::chrono::steady_clock::now() - started, std::chrono::seconds(10));
  for (const char* log : {"render.log", "worker.log"}) {
    const std::string text = readFile(dir / log);
    EXPECT_NE(text.find("--memory"), std::string::npos) << text;
    EXPECT_NE(text.find("at least"), std::string::npos) << text;
    EXPECT_EQ(text.find("worker 0"), std::string::npos) << text;   // no worker was started
  }
}

// nlohmann reports a number beyond a double's range without a position:
// the error names the file and the line.
TEST_F(ClientCommands, ANumberBeyondADoubleInBuildingJsonIsRefusedNamingFileAndLine) {
  const fs::path dir = dir_ / "overflow";
  const fs::path source = fs::path(PORTICO_SOURCE_DIR) / "tests/scenes/two_rooms";
  fs::create_directories(dir / "scene");
  for (const auto& entry : fs::directory_iterator(source))
    if (entry.path().extension() == ".obj") fs::copy_file(entry.path(), dir / "scene" / entry.path().filename());
  nlohmann::json scene = nlohmann::json::parse(readFile(source / "scene.json"));
  scene["overflow_marker"] = 12345.5;
  std::string text = scene.dump(2);
  text.replace(text.find("12345.5"), 7, "1e400");
  std::ofstream(dir / "scene" / "scene.json") << text;
  const auto line = 1 + std::count(text.begin(), text.begin() + std::ptrdiff_t(text.find("1e400")), '\n');
  const int code = runCommand(
      {kBin + "portico", "scene", "import", (dir / "scene" / "scene.json").string(), (dir / "store").string()},
      dir / "import.log");
  const std::string log = readFile(dir / "import.log");
  EXPECT_NE(code, 0) << log;
  EXPECT_NE(log.find((dir / "scene" / "scene.json").string() + ": not valid JSON: line " + std::to_string(line) +
                     ": the number 1e400 is beyond a double's range"),
            std::string::npos)
      << log;
  EXPECT_FALSE(fs::exists(dir / "store" / "scene.db"));
}

}  // namespace
}  // namespace portico
