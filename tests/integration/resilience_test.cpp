// Issue "lose nothing": real processes, real kills. A worker killed with
// SIGKILL at random moments, a coordinator killed mid-render, a worker that
// cannot see the scene store (cells over the wire), and workers whose memory
// budget is a tenth of the building: every job finishes with the bits of an
// undisturbed run and conserves its photons.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <csignal>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>
#include <thread>

#include "common/net/message.h"
#include "common/util/sqlite.h"
#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;

const std::string kUnshare = "/usr/bin/unshare";   // util-linux

class Resilience : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = makeTempDirectory("resilience");
    store_ = dir_ / "demo";
    ASSERT_EQ(generateDemoStore(store_, 5), "");
    LocalCluster cluster(dir_ / "reference", 1);
    const auto started = std::chrono::steady_clock::now();
    const auto status = cluster.render(store_, dir_ / "reference.exr", kPhotons, 1);
    referenceSeconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    ASSERT_EQ(status.value("state", ""), "done") << status.dump(2);
  }
  static void expectSameAsReference(const fs::path& image) {
    const auto stats = nlohmann::json::parse(readFile(image.string() + ".json"));
    expectConservation(stats);
    EXPECT_EQ(stats["photons"], nlohmann::json::parse(readFile(dir_ / "reference.exr.json"))["photons"]);
    EXPECT_EQ(differingFloats(image, dir_ / "reference.exr"), 0u);
  }
  // Submits the test job (image at dir/image.exr) with no worker to take it,
  // kills the coordinator, lets `whileDown` change its files, restarts it on
  // the same endpoint with two workers and waits: the job must be done, its
  // photon pass run once more, and its image the reference's, bit for bit.
  // Returns the coordinator's log, for what each test expects it to say.
  static std::string restartAfter(const fs::path& dir, const std::function<void(uint64_t job)>& whileDown) {
    LocalCluster cluster(dir, 0);
    const std::string endpoint = cluster.endpoint();
    const uint64_t job = cluster.submit(store_, dir / "image.exr", kPhotons, 1);
    cluster.killCoordinator();
    whileDown(job);
    cluster.startCoordinator(endpoint);
    cluster.addWorker({});
    cluster.addWorker({});
    const auto status = cluster.wait(job);
    const std::string log = readFile(dir / "coordinator.log");
    EXPECT_EQ(status.value("state", ""), "done") << status.dump(2) << log;
    if (status.value("state", "") != "done") return log;
    EXPECT_NE(log.find("running its photon pass again"), std::string::npos) << log;
    EXPECT_EQ(nlohmann::json::parse(readFile(dir / "image.exr.json"))["photon_pass_restarts"], 1);
    expectSameAsReference(dir / "image.exr");
    return log;
  }
  // Submits the test job (image at dir/image.exr) and polls until it is in
  // its render pass, with camera rays traced when asked; 0 if it finished
  // first or never got there.
  static uint64_t submitAndWaitForRender(LocalCluster& cluster, const fs::path& dir, bool withCameraRays) {
    const uint64_t job = cluster.submit(store_, dir / "image.exr", kPhotons, 1);
    for (int i = 0; i < 2000; ++i) {
      const auto status = cluster.status(job);
      const std::string state = status.value("state", "");
      if (state == "render" && (!withCameraRays || status["rays"]["camera"].get<int64_t>() > 0)) return job;
      if (state == "done") return 0;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return 0;
  }
  static constexpr uint64_t kPhotons = 60000;
  static fs::path dir_, store_;
  static double referenceSeconds_;
};
fs::path Resilience::dir_, Resilience::store_;
double Resilience::referenceSeconds_ = 0;

// kill -9 of a worker at a random moment of the job, for several seeds: the
// moments land in the photon pass, the render pass, mid-lease or idle.
TEST_F(Resilience, AWorkerKilledAtRandomMomentsChangesNoBit) {
  for (uint32_t seed : {11u, 12u, 13u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    std::mt19937 random(seed);
    const double killAt = std::uniform_real_distribution<double>(0.05, 0.9)(random) * referenceSeconds_;
    const fs::path dir = dir_ / ("kill-" + std::to_string(seed));
    LocalCluster cluster(dir, 3);
    const uint64_t job = cluster.submit(store_, dir / "image.exr", kPhotons, 1);
    std::this_thread::sleep_for(std::chrono::duration<double>(killAt));
    cluster.worker(0).kill(SIGKILL);
    cluster.worker(0).wait();
    const auto status = cluster.wait(job);
    ASSERT_EQ(status.value("state", ""), "done") << status.dump(2);
    expectSameAsReference(dir / "image.exr");
  }
}

// The existing restart test kills the coordinator in the photon pass; this
// one waits for the render pass (film partly written to jobs.db).
TEST_F(Resilience, ACoordinatorKilledMidRenderResumesWithTheSameBits) {
  const fs::path dir = dir_ / "restart-render";
  LocalCluster cluster(dir, 2);
  const std::string endpoint = cluster.endpoint();
  const uint64_t job = submitAndWaitForRender(cluster, dir, true);
  ASSERT_NE(job, 0u) << "the job never showed a render pass under way";
  cluster.killCoordinator();
  cluster.startCoordinator(endpoint);
  const auto status = cluster.wait(job);
  ASSERT_EQ(status.value("state", ""), "done") << status.dump(2);
  expectSameAsReference(dir / "image.exr");
}

// An operating-system crash can lose pages of a photon file that a
// committed row of jobs.db points to. Here: coordinator and workers killed
// mid-render, the job's photon file overwritten, everything restarted. The
// damaged batches fail their CRC when the new workers fetch them; the
// coordinator runs the job's photon pass again and the image comes out the
// same, bit for bit.
TEST_F(Resilience, ADamagedPhotonFileRunsThePhotonPassAgainWithTheSameBits) {
  const fs::path dir = dir_ / "damaged-photons";
  LocalCluster cluster(dir, 2);
  const std::string endpoint = cluster.endpoint();
  const uint64_t job = submitAndWaitForRender(cluster, dir, false);
  ASSERT_NE(job, 0u) << "the job never showed a render pass under way";
  cluster.killCoordinator();
  for (size_t i = 0; i < 2; ++i) {
    cluster.worker(i).kill(SIGKILL);
    cluster.worker(i).wait();
  }
  const fs::path photons = dir / ("jobs.db-photons/job-" + std::to_string(job) + ".bin");
  ASSERT_TRUE(fs::exists(photons));
  const auto size = fs::file_size(photons);
  ASSERT_GT(size, 0u);
  {
    std::ofstream out(photons, std::ios::binary | std::ios::in | std::ios::out);
    const std::string garbage(size_t(size), '\x5a');
    out.write(garbage.data(), std::streamsize(garbage.size()));
  }
  cluster.startCoordinator(endpoint);
  cluster.addWorker({});
  cluster.addWorker({});
  const auto status = cluster.wait(job);
  ASSERT_EQ(status.value("state", ""), "done") << status.dump(2) << readFile(dir / "coordinator.log");
  EXPECT_NE(readFile(dir / "coordinator.log").find("running its photon pass again"), std::string::npos)
      << readFile(dir / "coordinator.log");
  EXPECT_EQ(nlohmann::json::parse(readFile(dir / "image.exr.json"))["photon_pass_restarts"], 1);
  expectSameAsReference(dir / "image.exr");
}

// The same for the queued rays: an operating-system crash can lose pages of
// a batch file (jobs.db-batches/job-J-S.bin) that committed rows point to.
// Here the job is queued with no worker to take it, the coordinator killed,
// every batch file of the job overwritten, and the coordinator restarted
// with two workers: leasing finds the damage (nothing is leased), the job's
// photon pass runs again, and the image comes out the same, bit for bit.
TEST_F(Resilience, ADamagedBatchFileRunsThePhotonPassAgainWithTheSameBits) {
  const fs::path dir = dir_ / "damaged-batches";
  const std::string log = restartAfter(dir, [&](uint64_t job) {
    size_t damaged = 0;
    const std::string prefix = "job-" + std::to_string(job) + "-";
    for (const auto& entry : fs::directory_iterator(dir / "jobs.db-batches")) {
      if (entry.path().filename().string().rfind(prefix, 0) != 0) continue;
      const auto size = fs::file_size(entry.path());
      std::ofstream out(entry.path(), std::ios::binary | std::ios::in | std::ios::out);
      const std::string garbage(size_t(size), '\x5a');
      out.write(garbage.data(), std::streamsize(garbage.size()));
      damaged += size > 0;
    }
    EXPECT_GT(damaged, 0u) << "no batch file of job " << job << " in " << (dir / "jobs.db-batches");
  });
  EXPECT_NE(log.find("CRC mismatch"), std::string::npos) << log;
}

// A jobs.db left by a portico of 24-byte photon records (schema 4) with an
// unfinished job: the photon tables it holds cannot be read by today's
// workers, so the restarted coordinator runs that job's photon pass again,
// and the image is the same as ever.
TEST_F(Resilience, AJobBegunWithAnOlderPhotonRecordRunsItsPhotonPassAgainWithTheSameBits) {
  const fs::path dir = dir_ / "older-records";
  const std::string log = restartAfter(dir, [&](uint64_t job) {
    sql::Database db((dir / "jobs.db").string(), sql::Database::Mode::ReadWriteCreate);
    auto& update = db.prepare("UPDATE jobs SET photon_record_bytes = 24 WHERE id = ?");
    update.bind(1, int64_t(job));
    update.run();
  });
  EXPECT_NE(log.find("its photon tables hold 24-byte records of an older portico"), std::string::npos) << log;
}

// A cell whose work dies with every worker that takes it (here: workers
// that take a lease and vanish, as one that crashes on the cell's geometry
// would) is retried with rising attempt numbers, then fails its job with a
// message naming the cell: no endless retry.
TEST_F(Resilience, ACellLostWithItsWorkerThreeTimesFailsTheJobNamingTheCell) {
  const fs::path dir = dir_ / "lost-leases";
  ClusterOptions options;
  options.coordinatorExtra = {"--max-cell-failures", "3"};   // liveness: the harness's 2 s
  LocalCluster cluster(dir, 0, {}, options);
  const uint64_t job = cluster.submit(store_, dir / "image.exr", kPhotons, 1);
  zmq::context_t context(1);
  std::vector<uint32_t> attempts, cells;
  const auto sendEnvelope = [](zmq::socket_t& socket, capnp::MallocMessageBuilder& message) {
    socket.send(net::encode(message), zmq::send_flags::none);
  };
  const auto receive = [](zmq::socket_t& socket, wire::Envelope::Which which) -> std::unique_ptr<net::Decoded> {
    for (int i = 0; i < 100; ++i) {
      zmq::pollitem_t items[] = {{socket.handle(), 0, ZMQ_POLLIN, 0}};
      if (zmq::poll(items, 1, std::chrono::milliseconds(100)) != 1) continue;
      zmq::message_t message;
      if (!socket.recv(message)) continue;
      auto decoded = std::make_unique<net::Decoded>(message);
      if (decoded->envelope().which() == which) return decoded;
    }
    return nullptr;
  };
  for (int doomed = 0; doomed < 3; ++doomed) {
    zmq::socket_t socket(context, zmq::socket_type::dealer);
    socket.set(zmq::sockopt::linger, 0);
    useLocalKeys(socket, cluster.endpoint(), net::Role::Worker);
    socket.connect(cluster.endpoint());
    {
      capnp::MallocMessageBuilder message;
      auto hello = message.initRoot<wire::Envelope>().initHello();
      hello.setVersion(wire::PROTOCOL_VERSION);
      hello.setName("doomed-" + std::to_string(doomed));
      hello.setCores(1);
      hello.setMemoryBytes(uint64_t(1) << 30);
      sendEnvelope(socket, message);
    }
    ASSERT_TRUE(receive(socket, wire::Envelope::WELCOME)) << readFile(dir / "coordinator.log");
    {
      capnp::MallocMessageBuilder message;
      message.initRoot<wire::Envelope>().setReady();
      sendEnvelope(socket, message);
    }
    auto assign = receive(socket, wire::Envelope::ASSIGN);
    ASSERT_TRUE(assign) << readFile(dir / "coordinator.log");
    attempts.push_back(assign->envelope().getAssign().getAttempt());
    cells.push_back(assign->envelope().getAssign().getCell());
    socket.close();   // gone without a word, holding the lease
    // The next one comes once the coordinator has given up on this one.
    const std::string requeued = "lease " + std::to_string(assign->envelope().getAssign().getLease()) + " (";
    for (int i = 0; i < 100 && readFile(dir / "coordinator.log").find(requeued) == std::string::npos; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  const auto status = cluster.wait(job);
  ASSERT_EQ(attempts, (std::vector<uint32_t>{1, 2, 3})) << readFile(dir / "coordinator.log");
  EXPECT_EQ(cells[1], cells[0]);
  EXPECT_EQ(cells[2], cells[0]);
  EXPECT_EQ(status.value("state", ""), "failed") << status.dump(2);
  const std::string error = status.value("error", "");
  EXPECT_NE(error.find("cell " + std::to_string(cells[0]) + ":"), std::string::npos) << error;
  EXPECT_NE(error.find("lost 3 times"), std::string::npos) << error;
}

// A worker in its own mount namespace, where an empty tmpfs hides the scene
// store's directory: it can only get cells from the coordinator.
TEST_F(Resilience, AWorkerWithoutTheStoresFileSystemFetchesCellsOverTheWire) {
  if (runCommand({kUnshare, "-m", "/bin/true"}, dir_ / "unshare.log") != 0)
    GTEST_SKIP() << "cannot create a mount namespace here (unshare -m): " << readFile(dir_ / "unshare.log");
  const fs::path dir = dir_ / "over-the-wire";
  const fs::path cache = dir / "cache";
  LocalCluster cluster(dir, 0);
  const auto hideStore = [&](std::vector<std::string> argv) {
    std::string command = "mount -t tmpfs none '" + dir_.string() + "' && exec";
    for (const std::string& a : argv) command += " '" + a + "'";
    return std::vector<std::string>{kUnshare, "-m", "/bin/sh", "-c", command};
  };
  cluster.addWorker({"--cache-dir", cache.string()}, hideStore);
  const auto status = cluster.render(store_, dir / "image.exr", kPhotons, 1);
  ASSERT_EQ(status.value("state", ""), "done") << status.dump(2) << readFile(dir / "worker-0.log");
  expectSameAsReference(dir / "image.exr");
  // The cells came over the wire into the cache (the cache lives under
  // dir_, hidden from the worker too, so it wrote into its own tmpfs: check
  // the coordinator served files instead).
  EXPECT_EQ(readFile(dir / "worker-0.log").find("failed"), std::string::npos);
  const auto stats = nlohmann::json::parse(readFile(dir / "image.exr.json"));
  EXPECT_GT(stats["cells"]["bytes_read"].get<int64_t>(), 0);
}

// Peak resident memory of a live process, from /proc.
uint64_t peakResidentBytes(pid_t pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmHWM:", 0) == 0) {
      std::istringstream in(line.substr(6));
      uint64_t kib = 0;
      in >> kib;
      return kib * 1024;
    }
  return 0;
}

// Two floors of the tower: ~480 MB of cells against 46 MiB per worker.
TEST_F(Resilience, WorkersStayWithinTheirMemoryBudgetOnABuildingTenTimesLarger) {
  const fs::path dir = dir_ / "budget";
  const fs::path tower = dir_ / "tower";
  ASSERT_EQ(runCommand({kBin + "portico", "scene", "generate", "--preset", "tower", "--floors", "2", tower.string()},
                       dir_ / "tower.log"),
            0)
      << readFile(dir_ / "tower.log");
  uint64_t storeBytes = 0;
  for (const auto& entry : fs::recursive_directory_iterator(tower))
    if (entry.is_regular_file()) storeBytes += entry.file_size();
  const uint64_t budget = uint64_t(46) << 20;
  ASSERT_GE(storeBytes, 10 * budget);
  LocalCluster cluster(dir, 2, {{"--memory", "46MiB"}, {"--memory", "46MiB"}});
  const uint64_t job = cluster.submit(tower, dir / "image.exr", 100000, 1);
  const auto status = cluster.wait(job);
  ASSERT_EQ(status.value("state", ""), "done") << status.dump(2);
  for (size_t w = 0; w < 2; ++w) {
    const uint64_t peak = peakResidentBytes(cluster.worker(w).pid());
    std::cout << "worker " << w << ": peak RSS " << (peak >> 20) << " MiB, budget " << (budget >> 20) << " MiB, store "
              << (storeBytes >> 20) << " MiB\n";
    EXPECT_GT(peak, 0u);
    EXPECT_LE(double(peak), 1.25 * double(budget));
  }
  expectConservation(nlohmann::json::parse(readFile(dir / "image.exr.json")));
}

}  // namespace
}  // namespace portico
