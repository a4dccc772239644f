// Priorities and worker pools through real processes: `portico submit
// --priority`, `portico priority`, `portico-worker --tag` and `portico
// submit --require` against a coordinator and workers started by hand. The
// order of work changes; the bits of every image do not.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "common/util/sqlite.h"
#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;

class Scheduling : public DemoStoreSuite<Scheduling> {
 protected:
  // `portico submit` of the demo building at 96x64 with the given photons,
  // spp and seed, its own photon pass (--fresh-photons: a run alone must
  // not borrow the pass it is compared with), and `extra` (--priority,
  // --require); returns the job id.
  static uint64_t submit(const LocalCluster& cluster, const fs::path& dir, const std::string& name, uint64_t photons,
                         uint32_t spp, uint64_t seed, const std::vector<std::string>& extra = {}) {
    std::vector<std::string> argv{kBin + "portico", "submit", "--coordinator", cluster.endpoint(), store_.string(),
                                  "-o", (dir / (name + ".exr")).string(), "--accel", "grid", "--photons",
                                  std::to_string(photons), "--spp", std::to_string(spp), "--seed", std::to_string(seed),
                                  "--width", "96", "--height", "64", "--light-samples", "1", "--photon-k", "32",
                                  "--photon-radius", "0.5", "--gather", "2", "--fresh-photons"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    int code = -1;
    const std::string out = captureOutput(argv, dir, "submit-" + name, &code);
    EXPECT_EQ(code, 0) << readFile(dir / ("submit-" + name + ".log"));
    return std::stoull(out.empty() ? "0" : out);
  }
  // `portico ARGS...`: its exit code, its stdout in *out and its stderr returned.
  static std::string portico(const fs::path& dir, const std::string& name, const std::vector<std::string>& args,
                             int* code, std::string* out = nullptr) {
    std::vector<std::string> argv{kBin + "portico"};
    argv.insert(argv.end(), args.begin(), args.end());
    const std::string stdout_ = captureOutput(argv, dir, name, code);
    if (out) *out = stdout_;
    return readFile(dir / (name + ".log"));
  }
  // Polls the jobs until every one has ended; returns them in the order
  // they were seen done (jobs seen done in the same poll: by id).
  static std::vector<uint64_t> finishingOrder(LocalCluster& cluster, const std::vector<uint64_t>& jobs) {
    std::vector<uint64_t> order;
    const bool ended = waitUntil(
        [&] {
          for (uint64_t job : jobs) {
            if (std::count(order.begin(), order.end(), job)) continue;
            const std::string state = cluster.status(job).value("state", "");
            EXPECT_TRUE(state == "photons" || state == "render" || state == "done") << "job " << job << ": " << state;
            if (state == "done") order.push_back(job);
          }
          if (order.size() == jobs.size()) return true;
          std::this_thread::sleep_for(std::chrono::milliseconds(100));
          return false;
        },
        std::chrono::seconds(300));
    EXPECT_TRUE(ended) << "jobs still running after 300 s";
    return order;
  }
  // Which workers' leases each job's lease records name (jobs.db's lease
  // log, read once the coordinator has stopped: it holds the file exclusively).
  static std::map<uint64_t, std::set<std::string>> leaseWorkers(const fs::path& database) {
    std::map<uint64_t, std::set<std::string>> workers;
    sql::Database db(database.string(), sql::Database::Mode::ReadOnly);
    auto& s = db.prepare("SELECT DISTINCT job, worker FROM lease_log");
    while (s.step()) workers[uint64_t(s.columnInt(0))].insert(s.columnText(1));
    s.reset();
    return workers;
  }
};

// The long job's settings (~11 s on one worker), and the urgent one's
// (~1 s): 30x fewer photons, 24x fewer samples, another seed.
constexpr uint64_t kLongPhotons = 1000000, kUrgentPhotons = 30000;
constexpr uint32_t kLongSpp = 48, kUrgentSpp = 2;

TEST_F(Scheduling, AnUrgentJobSubmittedDuringALongOneFinishesFirstAndBothKeepTheirBits) {
  const fs::path dir = dir_ / "urgent";
  LocalCluster cluster(dir, 1);
  const uint64_t longJob = submit(cluster, dir, "long", kLongPhotons, kLongSpp, 7);
  // The long job holds the worker (its render under way) when the urgent one comes.
  ASSERT_TRUE(waitUntil(
      [&] {
        const auto s = cluster.status(longJob);
        return s.value("state", "") == "render" && s["progress"].value("camera_rays_done", int64_t{0}) > 0;
      },
      std::chrono::seconds(120)))
      << cluster.status(longJob).dump(2);
  const uint64_t urgentJob = submit(cluster, dir, "urgent", kUrgentPhotons, kUrgentSpp, 11, {"--priority", "10"});
  EXPECT_EQ(cluster.status(urgentJob).value("priority", -1), 10);
  EXPECT_EQ(cluster.status(longJob).value("priority", -1), 0);
  const std::vector<uint64_t> order = finishingOrder(cluster, {longJob, urgentJob});
  EXPECT_EQ(order, (std::vector<uint64_t>{urgentJob, longJob}));
  const auto urgentStatus = cluster.status(urgentJob), longStatus = cluster.status(longJob);
  expectConservation(urgentStatus);
  expectConservation(longStatus);

  // Each alone, on the idle cluster: the same bits.
  const uint64_t longAlone = submit(cluster, dir, "long-alone", kLongPhotons, kLongSpp, 7);
  ASSERT_EQ(cluster.wait(longAlone).value("state", ""), "done");
  const uint64_t urgentAlone = submit(cluster, dir, "urgent-alone", kUrgentPhotons, kUrgentSpp, 11);
  ASSERT_EQ(cluster.wait(urgentAlone).value("state", ""), "done");
  EXPECT_EQ(differingFloats(dir / "long.exr", dir / "long-alone.exr"), 0u);
  EXPECT_EQ(differingFloats(dir / "urgent.exr", dir / "urgent-alone.exr"), 0u);
  EXPECT_NE(differingFloats(dir / "long.exr", dir / "urgent.exr"), 0u);   // the comparison can tell images apart
  std::cout << "[ figures  ] long job " << longStatus["time_ms"].value("total", int64_t{0}) << " ms, urgent job "
            << urgentStatus["time_ms"].value("total", int64_t{0}) << " ms from its submit; alone: long "
            << cluster.status(longAlone)["time_ms"].value("total", int64_t{0}) << " ms, urgent "
            << cluster.status(urgentAlone)["time_ms"].value("total", int64_t{0}) << " ms\n";
}

TEST_F(Scheduling, RaisingAWaitingJobsPriorityRunsItBeforeAnOlderOneAndSurvivesARestart) {
  const fs::path dir = dir_ / "raise";
  LocalCluster cluster(dir, 1);
  const uint64_t running = submit(cluster, dir, "running", kLongPhotons, kLongSpp / 2, 7);
  const uint64_t older = submit(cluster, dir, "older", kUrgentPhotons, kUrgentSpp, 12);
  const uint64_t newer = submit(cluster, dir, "newer", kUrgentPhotons, kUrgentSpp, 13);
  int code = -1;
  std::string out;
  const std::string log =
      portico(dir, "raise", {"priority", "--coordinator", cluster.endpoint(), std::to_string(newer), "5"}, &code, &out);
  ASSERT_EQ(code, 0) << log;
  EXPECT_NE(out.find(fmt::format("job {}: ", newer)), std::string::npos) << out;
  EXPECT_NE(out.find("priority 5"), std::string::npos) << out;
  // Kept in jobs.db: a coordinator killed and restarted schedules alike.
  const std::string endpoint = cluster.endpoint();
  cluster.killCoordinator();
  cluster.startCoordinator(endpoint);   // the worker joins it again by itself
  EXPECT_EQ(cluster.status(newer).value("priority", -1), 5);
  portico(dir, "list", {"status", "--coordinator", cluster.endpoint()}, &code, &out);
  const size_t line = out.find(fmt::format("job {} ", newer));
  ASSERT_NE(line, std::string::npos) << out;
  EXPECT_NE(out.substr(line, out.find('\n', line) - line).find(" priority 5"), std::string::npos) << out;
  const std::vector<uint64_t> order = finishingOrder(cluster, {running, older, newer});
  ASSERT_EQ(order.size(), 3u);
  // Equal priorities keep the older first: only the raised job overtook.
  EXPECT_EQ(order.front(), newer);
  EXPECT_LT(std::find(order.begin(), order.end(), running), std::find(order.begin(), order.end(), older));
  for (uint64_t job : {running, older, newer}) expectConservation(cluster.status(job));
}

TEST_F(Scheduling, BadPriorityRequestsAreRefusedInOneLine) {
  const fs::path dir = dir_ / "refusals";
  LocalCluster cluster(dir, 0);
  const uint64_t job = submit(cluster, dir, "queued", kUrgentPhotons, kUrgentSpp, 7);
  const std::string jobText = std::to_string(job);
  struct Case {
    std::string name;
    std::vector<std::string> args;
    std::string says;
  };
  const std::vector<Case> cases{
      {"not-a-number", {jobText, "high"}, "'high' is not a whole number from -1000 to 1000"},
      {"fraction", {jobText, "1.5"}, "'1.5' is not a whole number"},
      {"out-of-range", {jobText, "5000"}, "5000 is out of range"},
      {"bad-job", {"first", "1"}, "'first' is not a whole number"},
      {"unknown-job", {"999", "1"}, "job 999 does not exist"},
      {"submit-out-of-range", {}, "--priority: 1001 is out of range"},
  };
  for (const Case& c : cases) {
    std::vector<std::string> args{"priority", "--coordinator", cluster.endpoint()};
    args.insert(args.end(), c.args.begin(), c.args.end());
    if (c.args.empty())
      args = {"submit",           "--coordinator", cluster.endpoint(), store_.string(), "-o",
              (dir / "x.exr").string(), "--priority", "1001"};
    int code = -1;
    const std::string log = portico(dir, c.name, args, &code);
    EXPECT_NE(code, 0) << c.name << ": " << log;
    ASSERT_NE(log.find(c.says), std::string::npos) << c.name << ": " << log;
    const std::string rest = log.substr(log.find('\n', log.find(c.says)) + 1);
    EXPECT_TRUE(rest.empty() || rest == "Run with --help for more information.\n") << c.name << ": " << log;
  }
  EXPECT_EQ(cluster.status(job).value("priority", -1), 0);   // nothing changed it
  EXPECT_EQ(cluster.status(0)["jobs"].size(), 1u);           // nor submitted anything

  // Another role than client or operator may not: a worker's key presented as a client's.
  const fs::path keys = dir / "keys", stolen = dir / "keys-worker-as-client";
  ASSERT_EQ(runCommand({kBin + "portico", "keys", "generate", keys.string()}, dir / "keys.log"), 0);
  fs::create_directories(stolen);
  fs::copy_file(keys / "coordinator.public", stolen / "coordinator.public");
  fs::copy_file(keys / "worker.secret", stolen / "client.secret");
  ClusterOptions options;
  options.coordinatorExtra = {"--keys", keys.string()};
  options.clientKeys = keys.string();
  LocalCluster keyed(dir / "keyed", 0, {}, options);
  int code = -1;
  std::string log = portico(dir, "worker-key",
                            {"priority", "--coordinator", keyed.endpoint(), "--keys", stolen.string(), "1", "3"}, &code);
  EXPECT_NE(code, 0) << log;
  EXPECT_NE(log.find("Priority refused: a worker may not send it (it needs a client or operator key)"),
            std::string::npos)
      << log;
  EXPECT_EQ(std::count(log.begin(), log.end(), '\n'), 1) << log;
  log = portico(dir, "client-key", {"priority", "--coordinator", keyed.endpoint(), "--keys", keys.string(), "1", "3"},
                &code);
  EXPECT_NE(code, 0);
  EXPECT_NE(log.find("job 1 does not exist"), std::string::npos) << log;   // admitted: the request itself answered
}

TEST_F(Scheduling, EachJobsLeasesGoOnlyToWorkersWithItsTagsAndAMissingTagIsWaitedFor) {
  const fs::path dir = dir_ / "pools";
  std::map<uint64_t, std::set<std::string>> expected;
  uint64_t red = 0, blue = 0, green = 0, untagged = 0;
  {
    LocalCluster cluster(dir, 2, {{"--tag", "red", "--tag", "big.mem"}, {"--tag", "blue"}});
    ASSERT_TRUE(waitUntil([&] { return cluster.status(0)["workers"].size() == 2; }, std::chrono::seconds(30)));
    int code = -1;
    std::string out;
    portico(dir, "workers", {"status", "--coordinator", cluster.endpoint()}, &code, &out);
    EXPECT_NE(out.find("w0 tags big.mem red"), std::string::npos) << out;
    EXPECT_NE(out.find("w1 tags blue"), std::string::npos) << out;

    green = submit(cluster, dir, "green", kUrgentPhotons, kUrgentSpp, 7, {"--require", "green"});
    red = submit(cluster, dir, "red", kUrgentPhotons, kUrgentSpp, 7, {"--require", "red", "--require", "big.mem"});
    blue = submit(cluster, dir, "blue", kUrgentPhotons, kUrgentSpp, 7, {"--require", "blue"});
    untagged = submit(cluster, dir, "untagged", kUrgentPhotons, kUrgentSpp, 7);
    for (uint64_t job : {red, blue, untagged}) EXPECT_EQ(cluster.wait(job).value("state", ""), "done");
    // Nothing for green: it says why, and no worker took any of it.
    auto waiting = cluster.status(green);
    EXPECT_EQ(waiting.value("state", ""), "photons") << waiting.dump(2);
    ASSERT_TRUE(waiting.contains("waiting")) << waiting.dump(2);
    EXPECT_EQ(waiting["waiting"], nlohmann::json::array({"needs tag green, no connected worker has it"}));
    EXPECT_EQ(waiting["progress"].value("photons_done", int64_t{-1}), 0);
    portico(dir, "green-status", {"status", "--coordinator", cluster.endpoint(), std::to_string(green)}, &code, &out);
    EXPECT_NE(out.find("waiting: needs tag green, no connected worker has it"), std::string::npos) << out;
    EXPECT_NE(out.find("requires tags green"), std::string::npos) << out;
    // A worker with the tag connects: the job runs, on it alone.
    cluster.addWorker({"--tag", "green"});
    EXPECT_EQ(cluster.wait(green).value("state", ""), "done");
    EXPECT_FALSE(cluster.status(green).contains("waiting"));
    // The job statistics name the workers whose Results it took.
    const auto workersOf = [&](uint64_t job) {
      std::set<std::string> names;
      const nlohmann::json status = cluster.status(job);
      for (const auto& [name, unused] : status["memory"]["workers"].items()) names.insert(name);
      return names;
    };
    EXPECT_EQ(workersOf(red), (std::set<std::string>{"w0"}));
    EXPECT_EQ(workersOf(blue), (std::set<std::string>{"w1"}));
    EXPECT_EQ(workersOf(green), (std::set<std::string>{"w2"}));
    expected = {{red, {"w0"}}, {blue, {"w1"}}, {green, {"w2"}}};
  }
  // The lease records agree (the untagged job's leases may go anywhere).
  auto leases = leaseWorkers(dir / "jobs.db");
  EXPECT_FALSE(leases[untagged].empty());
  leases.erase(untagged);
  EXPECT_EQ(leases, expected);
  // Same settings, each on another worker: the same bits.
  for (const char* name : {"blue", "green", "untagged"})
    EXPECT_EQ(differingFloats(dir / "red.exr", dir / (std::string(name) + ".exr")), 0u) << name;
}

TEST_F(Scheduling, BadTagsAreRefusedInOneLineByTheWorkerAndTheClient) {
  const fs::path dir = dir_ / "bad-tags";
  fs::create_directories(dir);
  int code = -1;
  for (const auto& [name, tag, says] : std::vector<std::tuple<std::string, std::string, std::string>>{
           {"space", "big mem", "tag 'big mem' holds a character other than"},
           {"dash", "-x", "tag '-x' does not start with a letter or digit"},
           {"long", std::string(65, 'a'), "is longer than 64 characters"}}) {
    const std::string log =
        portico(dir, "require-" + name,
                {"submit", "--coordinator", "tcp://127.0.0.1:1", store_.string(), "-o", (dir / "x.exr").string(),
                 "--require=" + tag},
                &code);
    EXPECT_NE(code, 0) << log;
    EXPECT_NE(log.find(says), std::string::npos) << name << ": " << log;
    const std::string rest = log.substr(log.find('\n', log.find(says)) + 1);
    EXPECT_TRUE(rest.empty() || rest == "Run with --help for more information.\n") << name << ": " << log;
    const int workerCode = runCommand({kBin + "portico-worker", "--connect", "tcp://127.0.0.1:1", "--tag=" + tag},
                                      dir / ("worker-" + name + ".log"));
    EXPECT_NE(workerCode, 0);
    EXPECT_NE(readFile(dir / ("worker-" + name + ".log")).find(says), std::string::npos)
        << readFile(dir / ("worker-" + name + ".log"));
  }
}

}  // namespace
}  // namespace portico
