// Issue "lose nothing": real processes, real kills. A worker killed with
// SIGKILL at random moments, a coordinator killed mid-render, a worker that
// cannot see the scene store (cells over the wire), and workers whose memory
// budget is a tenth of the building: every job finishes with the bits of an
// undisturbed run and conserves its photons.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <sched.h>
#include <sys/mount.h>

#include <csignal>
#include <cstring>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>
#include <thread>

#include "common/net/message.h"
#include "common/util/sqlite.h"
#include "tests/integration/service_harness.h"
#include "tests/support/process_memory.h"

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
    auto& update = db.prepare("UPDATE jobs SET photon_record_bytes = 16 WHERE id = ?");
    update.bind(1, int64_t(job));
    update.run();
  });
  EXPECT_NE(log.find("its photon tables hold 16-byte records of an older portico"), std::string::npos) << log;
}

// A cell whose work dies with every worker that takes it (here: workers
// that take a lease and vanish without a word, as one killed by the memory
// the cell exhausts would) is retried with rising attempt numbers, then
// fails its job with a message naming the cell: no endless retry. The limit
// is --max-lost-leases (10 by default: healthy workers are lost too), here 3.
TEST_F(Resilience, ACellLostWithItsWorkerThreeTimesFailsTheJobNamingTheCell) {
  const fs::path dir = dir_ / "lost-leases";
  ClusterOptions options;
  options.coordinatorExtra = {"--max-lost-leases", "3"};   // liveness: the harness's 2 s
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
    // And once the cell's back-off (0.5 s, then 1 s) has passed: it gets the same cell.
    std::this_thread::sleep_for(std::chrono::milliseconds((500 << doomed) + 200));
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

// Healthy workers killed from outside (SIGKILL, as the OOM killer or a
// preempted node does) while holding leases, three times in a row: a lost
// worker is not a cell that kills its workers. The job waits out a back-off
// between the retries and finishes with the reference's bits, where one
// limit for both kinds of failure would fail it at the third loss.
TEST_F(Resilience, ThreeOutsideKillsOfHealthyWorkersDoNotFailTheJob) {
  const fs::path dir = dir_ / "outside-kills";
  ClusterOptions options;
  options.coordinatorExtra = {"--log-level", "debug"};   // each lease is logged as it is sent
  LocalCluster cluster(dir, 0, {}, options);
  const uint64_t job = cluster.submit(store_, dir / "image.exr", kPhotons, 1);
  for (size_t k = 0; k < 3; ++k) {
    const std::string name = "w" + std::to_string(k);
    cluster.addWorker({});
    // Killed the moment its first lease is sent: it dies holding it.
    ASSERT_TRUE(waitUntil([&] { return readFile(dir / "coordinator.log").find("-> " + name + ":") != std::string::npos; },
                          std::chrono::seconds(20)))
        << readFile(dir / "coordinator.log");
    cluster.worker(k).kill(SIGKILL);
    cluster.worker(k).wait();
    ASSERT_TRUE(waitUntil([&] { return readFile(dir / "coordinator.log").find("worker " + name + " presumed dead") !=
                                       std::string::npos; },
                          std::chrono::seconds(20)))
        << readFile(dir / "coordinator.log");
    // The next worker comes once the lost cells' back-off (0.5 s, 1 s) has
    // passed, so that it is given the same cells, on their next attempt.
    std::this_thread::sleep_for(std::chrono::milliseconds((500 << k) + 200));
  }
  cluster.addWorker({});
  const auto status = cluster.wait(job);
  ASSERT_EQ(status.value("state", ""), "done") << status.dump(2) << readFile(dir / "coordinator.log");
  expectSameAsReference(dir / "image.exr");
  EXPECT_NE(readFile(dir / "coordinator.log").find("attempt 3"), std::string::npos) << readFile(dir / "coordinator.log");
}

// The other side: a cell that crashes every worker tracing it. Each worker
// reports the crash before it dies (a Failure), which counts against the
// cell, so the job fails after --max-cell-failures (3) crashes, naming the
// cell and the crash, without waiting for ten lost leases.
TEST_F(Resilience, ACellThatCrashesItsWorkersFailsTheJobAfterThreeReportedCrashes) {
  const fs::path dir = dir_ / "crashing-cell";
  LocalCluster cluster(dir, 0);
  const uint64_t job = cluster.submit(store_, dir / "image.exr", kPhotons, 1);
  for (size_t k = 0; k < 3; ++k) {
    cluster.addWorker({"--crash-in-lease", "1"});
    ASSERT_TRUE(waitUntil([&] { return !cluster.worker(k).running(); }, std::chrono::seconds(20)))
        << readFile(dir / ("worker-" + std::to_string(k) + ".log"));
    EXPECT_EQ(cluster.worker(k).exitCode(), 128 + SIGSEGV);
    // Its other leases are lost with it; once it is given up, the next
    // worker comes after the cell's back-off (doubling with the crash and
    // the loss of each round: 1 s, then 4 s), so that it gets the same cell.
    if (k == 2) break;
    const std::string name = "w" + std::to_string(k);
    ASSERT_TRUE(waitUntil([&] { return readFile(dir / "coordinator.log").find("worker " + name + " presumed dead") !=
                                       std::string::npos; },
                          std::chrono::seconds(20)));
    std::this_thread::sleep_for(std::chrono::milliseconds(1000 << (2 * k)));
  }
  const auto status = cluster.wait(job);
  EXPECT_EQ(status.value("state", ""), "failed") << status.dump(2) << readFile(dir / "coordinator.log");
  const std::string error = status.value("error", "");
  EXPECT_NE(error.find("the worker crashed tracing it"), std::string::npos) << error;
  EXPECT_NE(error.find("(failed 3 times)"), std::string::npos) << error;
}

// The scene store moved away for a while (an unmounted share): the workers'
// leases fail, but the coordinator cannot read the store either, so the
// failures are the store's, not the cells': nothing is counted, the cells
// wait with back-off, and once the store is back the job finishes with the
// reference's bits, instead of failing after three failures milliseconds apart.
TEST_F(Resilience, AStoreThatVanishesForAWhileDoesNotFailTheJob) {
  const fs::path dir = dir_ / "store-away";
  const fs::path store = dir / "store", away = dir / "store.away";
  fs::create_directories(dir);
  fs::copy(store_, store, fs::copy_options::recursive);
  LocalCluster cluster(dir, 0);
  const uint64_t job = cluster.submit(store, dir / "image.exr", kPhotons, 1);
  fs::rename(store, away);
  cluster.addWorker({});
  ASSERT_TRUE(waitUntil([&] { return readFile(dir / "coordinator.log").find("not counted") != std::string::npos; },
                        std::chrono::seconds(20)))
      << readFile(dir / "coordinator.log");
  std::this_thread::sleep_for(std::chrono::seconds(2));
  EXPECT_EQ(cluster.status(job).value("state", ""), "photons") << readFile(dir / "coordinator.log");
  fs::rename(away, store);
  const auto status = cluster.wait(job);
  ASSERT_EQ(status.value("state", ""), "done") << status.dump(2) << readFile(dir / "coordinator.log");
  expectSameAsReference(dir / "image.exr");
}

// A store deleted for good: the job's status says so from the first
// heartbeat on, and the job fails after --store-gone-timeout with that
// message, instead of waiting for ever with idle workers and a growing ETA.
TEST_F(Resilience, AJobWhoseStoreIsGoneSaysWhyItWaitsAndFailsAfterTheTimeout) {
  const fs::path dir = dir_ / "store-gone";
  fs::create_directories(dir);
  fs::copy(store_, dir / "store", fs::copy_options::recursive);
  const fs::path store = fs::canonical(dir / "store");
  ClusterOptions options;
  options.coordinatorExtra = {"--store-gone-timeout", "4"};
  LocalCluster cluster(dir, 0, {}, options);
  const uint64_t job = cluster.submit(store, dir / "image.exr", kPhotons, 1);
  fs::remove_all(store);
  cluster.addWorker({});
  nlohmann::json status;
  ASSERT_TRUE(waitUntil(
      [&] {
        status = cluster.status(job);
        return status.contains("waiting") && status["waiting"].dump().find("store cannot be read since") != std::string::npos;
      },
      std::chrono::seconds(10)))
      << status.dump(2) << readFile(dir / "coordinator.log");
  EXPECT_NE(status["waiting"].dump().find(store.string() + "/scene.db"), std::string::npos) << status.dump(2);
  EXPECT_FALSE(status.contains("eta_s")) << status.dump(2);
  status = cluster.wait(job);
  ASSERT_EQ(status.value("state", ""), "failed") << status.dump(2);
  const std::string error = status.value("error", "");
  EXPECT_NE(error.find("store " + store.string() + " cannot be read since"), std::string::npos) << error;
  EXPECT_NE(error.find("--store-gone-timeout"), std::string::npos) << error;
}

// A real full disk: jobs.db and its files on a 32 MiB tmpfs, filled while
// a job runs. Writes fail (ENOSPC on the photon and batch files,
// SQLITE_FULL on the WAL); the coordinator undoes each failed round,
// pauses leasing with back-off and logs a line now and then, counts no
// failure against any cell, and resumes by itself when space is freed: the
// image has the reference's bits: no twenty lines a second, no failure
// counted against a cell, no stall until a restart. The tmpfs is
// mounted in a mount namespace of this test process alone, so it goes with
// the process; skipped where mounting is not allowed.
TEST_F(Resilience, AFullDiskPausesTheJobWhichResumesByItselfWithTheSameBits) {
  const fs::path dir = dir_ / "full-disk";
  fs::create_directories(dir);
  if (::unshare(CLONE_NEWNS) != 0 || ::mount(nullptr, "/", nullptr, MS_REC | MS_PRIVATE, nullptr) != 0 ||
      ::mount("portico-test", dir.c_str(), "tmpfs", 0, "size=32m") != 0)
    GTEST_SKIP() << "cannot mount a tmpfs here (needs root in a mount namespace): " << std::strerror(errno);
  LocalCluster cluster(dir, 0);
  const uint64_t job = cluster.submit(store_, dir / "image.exr", kPhotons, 1);
  // Fill the disk, then free a little: small commits fit, a Result's photons do not.
  const fs::path filler = dir / "filler";
  {
    std::ofstream out(filler, std::ios::binary);
    const std::string chunk(1 << 20, '\0');
    while (out.write(chunk.data(), std::streamsize(chunk.size()))) {
    }
  }
  fs::resize_file(filler, fs::file_size(filler) - (256 << 10));
  cluster.addWorker({});
  cluster.addWorker({});
  ASSERT_TRUE(waitUntil([&] { return readFile(dir / "coordinator.log").find("cannot write jobs.db") != std::string::npos; },
                        std::chrono::seconds(20)))
      << readFile(dir / "coordinator.log");
  std::this_thread::sleep_for(std::chrono::seconds(3));
  const auto during = cluster.status(job);
  EXPECT_EQ(during.value("state", ""), "photons") << during.dump(2);
  // Its status says why it waits, and gives no ETA that would only grow.
  ASSERT_TRUE(during.contains("waiting")) << during.dump(2);
  const std::string waiting = during["waiting"].dump();
  EXPECT_NE(waiting.find("disk full on " + dir.string()), std::string::npos) << waiting;
  EXPECT_NE(waiting.find("rounds undone"), std::string::npos) << waiting;
  EXPECT_FALSE(during.contains("eta_s")) << during.dump(2);
  int code = -1;
  const std::string text = captureOutput({kBin + "portico", "status", "--coordinator", cluster.endpoint(),
                                          std::to_string(job)},
                                         dir_, "full-disk-status", &code);
  EXPECT_EQ(code, 0) << readFile(dir_ / "full-disk-status.log");
  EXPECT_NE(text.find("waiting: disk full on "), std::string::npos) << text;
  const std::string log = readFile(dir / "coordinator.log");
  size_t lines = 0;
  for (size_t at = log.find("[error]"); at != std::string::npos; at = log.find("[error]", at + 1)) ++lines;
  EXPECT_LE(lines, 3u) << log;
  EXPECT_EQ(log.find("rejected the result"), std::string::npos) << log;   // no cell failure counted
  fs::remove(filler);
  const auto status = cluster.wait(job);
  ASSERT_EQ(status.value("state", ""), "done") << status.dump(2) << readFile(dir / "coordinator.log");
  expectSameAsReference(dir / "image.exr");
  EXPECT_NE(readFile(dir / "coordinator.log").find("can be written again"), std::string::npos);
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

// Two floors of the tower (~480 MB of cells), generated once for the
// tests that hold workers to their --memory.
fs::path twoFloorTower() {
  static const fs::path tower = [] {
    const fs::path store = makeTempDirectory("resilience-tower") / "tower";
    const fs::path log = store.parent_path() / "tower.log";
    if (runCommand({kBin + "portico", "scene", "generate", "--preset", "tower", "--floors", "2", store.string()}, log) != 0)
      throw std::runtime_error("cannot generate the tower: " + readFile(log));
    return store;
  }();
  return tower;
}

// Renders two tower floors with two workers at --memory `mib` MiB and
// checks from the job's statistics that it completes, conserves every
// photon, and that each worker's peak (VmHWM, sent with its Results; at
// most the process's own peak to date, from /proc) lies between `least`
// and `most` times its --memory. Returns the statistics.
nlohmann::json renderWithinMemory(const fs::path& dir, uint64_t mib, uint64_t photons, double least, double most) {
  const uint64_t budget = mib << 20;
  const std::string memory = std::to_string(mib) + "MiB";
  LocalCluster cluster(dir, 2, {{"--memory", memory}, {"--memory", memory}});
  const auto status = cluster.wait(cluster.submit(twoFloorTower(), dir / "image.exr", photons, 1));
  EXPECT_EQ(status.value("state", ""), "done") << status.dump(2);
  const auto stats = nlohmann::json::parse(readFile(dir / "image.exr.json"));
  expectConservation(stats);
  const auto& workers = stats["memory"]["workers"];
  EXPECT_EQ(workers.size(), 2u) << stats["memory"].dump(2);
  for (const auto& [name, w] : workers.items()) {
    const uint64_t reported = w.value("peak_rss_bytes", uint64_t(0));
    std::cout << name << ": peak RSS " << (reported >> 20) << " MiB of --memory " << mib << " MiB ("
              << double(reported) / double(budget) << " x)\n";
    EXPECT_EQ(w.value("budget_bytes", uint64_t(0)), budget);
    EXPECT_GT(double(reported), least * double(budget)) << name;
    EXPECT_LE(double(reported), most * double(budget)) << name;
  }
  for (size_t w = 0; w < 2; ++w) {
    const uint64_t peak = testing_support::peakResidentBytes(cluster.worker(w).pid());
    EXPECT_GT(peak, 0u);
    EXPECT_LE(double(peak), most * double(budget));
    // It said at start how it shares its --memory out.
    EXPECT_NE(readFile(dir / ("worker-" + std::to_string(w) + ".log"))
                  .find("--memory " + std::to_string(mib) + " MiB: the worker itself"),
              std::string::npos);
  }
  EXPECT_GT(stats["memory"].value("coordinator_peak_rss_bytes", 0), 0);
  return stats;
}

// Two floors of the tower: ~480 MB of cells against 46 MiB per worker.
TEST_F(Resilience, WorkersStayWithinTheirMemoryBudgetOnABuildingTenTimesLarger) {
  uint64_t storeBytes = 0;
  for (const auto& entry : fs::recursive_directory_iterator(twoFloorTower()))
    if (entry.is_regular_file()) storeBytes += entry.file_size();
  ASSERT_GE(storeBytes, uint64_t(10 * 46) << 20);
  const auto stats = renderWithinMemory(dir_ / "budget", 46, 100000, 0.2, 1.25);
  // Every cell with work was loaded; each load of a cell read its file.
  EXPECT_GT(stats["cells"].value("bytes_read", int64_t(0)), int64_t(storeBytes / 4));
  EXPECT_EQ(stats["cells"].value("loaded", 0),
            stats["cells"].value("distinct_loaded", 0) + stats["cells"].value("reloads", 0));
  EXPECT_GT(stats["disk"].value("photon_file_bytes", 0), 0);
}

// --memory bounds the whole worker, at the small end too: two floors of
// the tower at 128 MiB per worker, with photon maps of up to ~400 K
// photons whose assembly takes ~200 bytes a photon of scratch beside the
// map. A load or an assembly first makes room for what it adds beside the
// worker's measured resident size (CellCache::makeRoom); counting only
// the cache's entries, the workers peaked at 1.26-1.37 x their --memory
// here, the freed scratch of each assembly kept resident by the heap.
// Most of the budget is used (at least 0.6 x): the cells do not fit, and a
// bound met by holding nothing would prove little.
TEST_F(Resilience, EveryWorkerPeaksWithinATenthOfItsMemoryAt128MiB) {
  renderWithinMemory(dir_ / "budget-128", 128, 2000000, 0.6, 1.1);
}

}  // namespace
}  // namespace portico
