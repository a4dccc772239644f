// Another user of the same machine against a coordinator run by root, as
// real processes of uid nobody: it can neither submit, nor read a file
// through a store's symbolic link, nor write where it may not, nor shut
// the coordinator down, whether the coordinator listens on tcp:// (no
// --keys: the per-user keys) or on ipc://. Skipped where the test cannot
// switch to another uid (not root, or no setpriv), or where uid nobody
// cannot reach the temporary folder (a TMPDIR inside a private folder).
#include <capnp/message.h>
#include <grp.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <thread>

#include "common/net/client.h"
#include "common/net/message.h"
#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;

constexpr uid_t kNobody = 65534;
constexpr gid_t kNogroup = 65534;
const char* const kSecret = "TOP SECRET: only root may read this";

class LocalUsers : public ::testing::Test {
 protected:
  void SetUp() override {
    if (::geteuid() != 0) GTEST_SKIP() << "needs root: the attacker runs as uid nobody (setpriv)";
    if (::access("/usr/bin/setpriv", X_OK) != 0) GTEST_SKIP() << "needs /usr/bin/setpriv (util-linux)";
    dir_ = makeTempDirectory(std::string("local-users-") +
                             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    // nobody enters it (the tests' files say what it may read and write), whatever the umask.
    fs::permissions(dir_, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                              fs::perms::others_read | fs::perms::others_exec);
    // The programs nobody runs, copied where it can reach them: the build
    // folder may lie in a private folder (a clone in root's 0700 home, or in
    // a folder of mktemp -d), which only root may enter.
    bin_ = dir_ / "bin";
    fs::create_directories(bin_);
    for (const char* program : {"portico", "portico-worker", "portico_image_formats.so"})
      fs::copy_file(kBin + program, bin_ / program);
    const fs::path probe = bin_ / "portico";
    if (forkAsNobody([&] { return ::access(probe.c_str(), X_OK) == 0 ? 0 : 1; }) != 0)
      GTEST_SKIP() << "uid nobody cannot reach " << dir_ << ": the temporary folder (TMPDIR) lies in a folder "
                   << "only its owner may enter";
    // The coordinator's per-user keys (root's), here rather than in ~/.config.
    ::setenv("PORTICO_KEYS", (dir_ / "root-keys").c_str(), 1);
    std::ofstream(dir_ / "secret.txt") << kSecret;
    fs::permissions(dir_ / "secret.txt", fs::perms::owner_read | fs::perms::owner_write);
    fs::create_directories(dir_ / "root-only");
    fs::permissions(dir_ / "root-only", fs::perms::owner_all);
    // nobody's home: its own store and whatever it makes.
    home_ = dir_ / "nobody";
    fs::create_directories(home_);
    ASSERT_EQ(generateDemoStore(home_ / "store", 3), "");
  }
  void TearDown() override { ::unsetenv("PORTICO_KEYS"); }

  // Hands nobody's home over to it (after the test has put its files there).
  void giveHomeToNobody() {
    for (const auto& entry : fs::recursive_directory_iterator(home_)) (void)::lchown(entry.path().c_str(), kNobody, kNogroup);
    ASSERT_EQ(::chown(home_.c_str(), kNobody, kNogroup), 0);
  }

  // A program of nobody's, as it runs it: the copy it can reach.
  std::string program(const std::string& name) const { return (bin_ / name).string(); }

  // `argv` run as uid nobody, its per-user keys in its own home.
  std::vector<std::string> asNobody(const std::vector<std::string>& argv) const {
    std::vector<std::string> wrapped{"/usr/bin/setpriv",  "--reuid=nobody", "--regid=nogroup", "--clear-groups",
                                     "/usr/bin/env", "HOME=" + home_.string(),
                                     "PORTICO_KEYS=" + (home_ / "keys").string()};
    wrapped.insert(wrapped.end(), argv.begin(), argv.end());
    return wrapped;
  }

  // Runs `attack` in a child process of uid nobody; returns its exit status.
  static int forkAsNobody(const std::function<int()>& attack) {
    const pid_t pid = ::fork();
    if (pid == 0) {
      int code = 100;
      if (::setgroups(0, nullptr) == 0 && ::setgid(kNogroup) == 0 && ::setuid(kNobody) == 0) {
        try {
          code = attack();
        } catch (...) {
          code = 101;
        }
      }
      std::_Exit(code);
    }
    int status = 0;
    ::waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }

  // Sends one Shutdown from uid nobody, as a peer without keys would.
  static void shutdownAsNobody(const std::string& endpoint) {
    forkAsNobody([&] {
      zmq::context_t context(1);
      zmq::socket_t socket(context, zmq::socket_type::dealer);
      socket.set(zmq::sockopt::linger, 1000);
      socket.connect(endpoint);
      capnp::MallocMessageBuilder message;
      message.initRoot<wire::Envelope>().setShutdown();
      (void)socket.send(net::encode(message), zmq::send_flags::dontwait);
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
      return 0;
    });
  }

  // Plays a coordinator as uid nobody for `seconds`, bound to `endpoint`
  // (its real address written to `boundFile`): it welcomes any worker,
  // leases it a cell, and answers its first file request with a chunk named
  // to leave the worker's cache for `escape`.
  static void impostorAsNobody(const std::string& endpoint, const fs::path& boundFile, const std::string& escape,
                               int seconds) {
    forkAsNobody([&] {
      zmq::context_t context(1);
      zmq::socket_t router(context, zmq::socket_type::router);
      router.set(zmq::sockopt::linger, 0);
      router.bind(endpoint);
      std::ofstream(boundFile) << router.get(zmq::sockopt::last_endpoint);
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
      while (std::chrono::steady_clock::now() < deadline) {
        zmq::pollitem_t items[] = {{router.handle(), 0, ZMQ_POLLIN, 0}};
        zmq::poll(items, 1, std::chrono::milliseconds(100));
        if (!(items[0].revents & ZMQ_POLLIN)) continue;
        zmq::message_t identity, frame;
        if (!router.recv(identity) || !identity.more() || !router.recv(frame)) continue;
        const net::Decoded decoded(std::move(frame));
        const auto reply = [&](capnp::MallocMessageBuilder& message) {
          zmq::message_t to;
          to.copy(identity);
          router.send(to, zmq::send_flags::sndmore);
          router.send(net::encode(message), zmq::send_flags::none);
        };
        if (decoded.envelope().isHello()) {
          capnp::MallocMessageBuilder welcome;
          auto w = welcome.initRoot<wire::Envelope>().initWelcome();
          w.setVersion(wire::PROTOCOL_VERSION);
          w.setHeartbeatMs(250);
          w.setMaxFrameBytes(1 << 20);
          reply(welcome);
          capnp::MallocMessageBuilder assign;
          auto a = assign.initRoot<wire::Envelope>().initAssign();
          a.setLease(1);
          a.setJob(1);
          a.setCell(0);
          a.initSpec().setStore("/srv/store");
          reply(assign);
        } else if (decoded.envelope().isFetchFile()) {
          capnp::MallocMessageBuilder chunk;
          auto c = chunk.initRoot<wire::Envelope>().initFileChunk();
          c.setStore(decoded.envelope().getFetchFile().getStore());
          c.setPath(escape);
          const std::string planted = "written by uid nobody's impostor";
          c.setTotalBytes(planted.size());
          c.setData(capnp::Data::Reader(reinterpret_cast<const kj::byte*>(planted.data()), planted.size()));
          reply(chunk);
        }
      }
      return 0;
    });
  }

  bool anyFileHolds(const fs::path& root, const std::string& text) const {
    if (!fs::exists(root)) return false;
    for (const auto& entry : fs::recursive_directory_iterator(root))
      if (entry.is_regular_file() && readFile(entry.path()).find(text) != std::string::npos) return true;
    return false;
  }

  fs::path dir_, home_, bin_;
};

TEST_F(LocalUsers, AnotherUserCanNeitherSubmitNorReadNorWriteNorShutDownATcpCoordinatorWithoutKeys) {
  // Its store: a demo building whose every cell is a link to root's secret.
  fs::copy(home_ / "store", home_ / "linked-store", fs::copy_options::recursive);
  for (const auto& cell : fs::directory_iterator(home_ / "linked-store" / "cells")) {
    fs::remove(cell.path());
    fs::create_symlink(dir_ / "secret.txt", cell.path());
  }
  giveHomeToNobody();
  LocalCluster cluster(dir_ / "cluster", 0);   // tcp://127.0.0.1:*, no --keys
  int code = -1;

  // Submitting the linked store, then fetching its cells as a worker with a disk cache.
  captureOutput(asNobody({program("portico"), "submit", "--coordinator", cluster.endpoint(), "--timeout", "3",
                          (home_ / "linked-store").string(), "-o", (home_ / "linked.png").string()}),
                dir_, "submit-linked", &code);
  EXPECT_NE(code, 0) << readFile(dir_ / "submit-linked.log");
  {
    ChildProcess worker(asNobody({program("portico-worker"), "--connect", cluster.endpoint(), "--name", "intruder",
                                  "--cache-dir", (home_ / "cache").string(), "--memory", "256MiB"}),
                        (dir_ / "intruder.log").string());
    std::this_thread::sleep_for(std::chrono::seconds(3));
    EXPECT_EQ(cluster.status(0)["workers"].size(), 0u) << readFile(dir_ / "intruder.log");
  }
  EXPECT_FALSE(anyFileHolds(home_ / "cache", kSecret)) << "a file-fetch handed root's secret to uid nobody";

  // Writing where only root may: a worker of root's renders whatever is accepted.
  cluster.addWorker({});
  const std::string submitted =
      captureOutput(asNobody({program("portico"), "submit", "--coordinator", cluster.endpoint(), "--timeout", "3",
                              (home_ / "store").string(), "-o", (dir_ / "root-only" / "x" / "y.png").string(),
                              "--photons", "2000", "--spp", "1", "--width", "32", "--height", "24"}),
                    dir_, "submit-root-only", &code);
  EXPECT_NE(code, 0) << readFile(dir_ / "submit-root-only.log");
  if (code == 0) cluster.wait(std::stoull(submitted));   // accepted: let it show what it writes
  EXPECT_FALSE(fs::exists(dir_ / "root-only" / "x")) << "directories created on behalf of uid nobody";

  // With keys of its own, it is refused all the same.
  ASSERT_EQ(runCommand(asNobody({program("portico"), "keys", "generate", (home_ / "keys").string()}), dir_ / "keys.log"), 0)
      << readFile(dir_ / "keys.log");
  captureOutput(asNobody({program("portico"), "status", "--coordinator", cluster.endpoint(), "--timeout", "2"}), dir_,
                "status-own-keys", &code);
  EXPECT_NE(code, 0);
  EXPECT_NE(readFile(dir_ / "status-own-keys.log").find("wrong --keys, or coordinator down"), std::string::npos)
      << readFile(dir_ / "status-own-keys.log");

  // Shutdown: the coordinator goes on serving.
  shutdownAsNobody(cluster.endpoint());
  captureOutput(asNobody({program("portico"), "shutdown", "--coordinator", cluster.endpoint()}), dir_, "shutdown", &code);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  EXPECT_NO_THROW(cluster.status(0)) << readFile(dir_ / "cluster" / "coordinator.log");
  const std::string log = readFile(dir_ / "cluster" / "coordinator.log");
  EXPECT_EQ(log.find("shutdown requested"), std::string::npos) << log;
  EXPECT_EQ(log.find("job 1 submitted"), std::string::npos) << log;
}

TEST_F(LocalUsers, AnIpcCoordinatorWithoutKeysAdmitsOnlyItsOwnUser) {
  // A socket in a directory anyone may write (sticky, as /tmp): the peer's uid is what keeps nobody out.
  const fs::path open = dir_ / "open";
  fs::create_directories(open);
  fs::permissions(open, fs::perms::all | fs::perms::sticky_bit);
  giveHomeToNobody();
  ClusterOptions options;
  options.listen = "ipc://" + (open / "coordinator.sock").string();
  LocalCluster cluster(dir_ / "cluster", 1, {}, options);
  // And a socket anyone may write to (libzmq leaves it to the umask).
  fs::permissions(open / "coordinator.sock", fs::perms::all);
  int code = -1;
  captureOutput(asNobody({program("portico"), "submit", "--coordinator", cluster.endpoint(), "--timeout", "3",
                          (home_ / "store").string(), "-o", (home_ / "out.png").string(), "--photons", "2000",
                          "--spp", "1"}),
                dir_, "submit", &code);
  EXPECT_NE(code, 0) << readFile(dir_ / "submit.log");
  // Refused by the coordinator, not by the file system: the command ran and got no answer.
  EXPECT_NE(readFile(dir_ / "submit.log").find("no answer from"), std::string::npos) << readFile(dir_ / "submit.log");
  shutdownAsNobody(cluster.endpoint());
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  // Root, and the coordinator's own worker, are served.
  const auto status = cluster.status(0);
  EXPECT_EQ(status["jobs"].size(), 0u) << status.dump(2);
  EXPECT_EQ(status["workers"].size(), 1u) << status.dump(2);
  const std::string log = readFile(dir_ / "cluster" / "coordinator.log");
  EXPECT_NE(log.find("uid 65534 is not this coordinator's user (uid 0)"), std::string::npos) << log;
  EXPECT_EQ(log.find("shutdown requested"), std::string::npos) << log;
}

TEST_F(LocalUsers, AnOutputDirectoryTheSubmittingUserMayNotWriteIsRefusedBeforeAnythingIsSent) {
  giveHomeToNobody();
  int code = -1;
  // No coordinator listens there: the client refuses before it connects.
  captureOutput(asNobody({program("portico"), "submit", "--coordinator", "ipc://" + (dir_ / "none.sock").string(),
                          (home_ / "store").string(), "-o", dir_.string() + "/y.png"}),
                dir_, "submit", &code);
  EXPECT_NE(code, 0);
  const std::string log = readFile(dir_ / "submit.log");
  EXPECT_NE(log.find("output " + dir_.string() + "/y.png: directory " + dir_.string() + " is not writable by uid 65534"),
            std::string::npos)
      << log;
}

}  // namespace
}  // namespace portico

namespace portico {
namespace {

// A worker run by root with a disk cache, and a coordinator played by uid
// nobody: on ipc:// it binds the socket's path in a folder anyone may write
// (as /tmp) after the worker started; on tcp:// it listens without CURVE
// for a worker that has no coordinator key. The worker must never take a
// lease from it, let alone write the file its chunk names outside the cache.
TEST_F(LocalUsers, AWorkerTakesNoOrdersFromAnImpostorOfAnotherUser) {
  const fs::path open = dir_ / "open";
  fs::create_directories(open);
  fs::permissions(open, fs::perms::all | fs::perms::sticky_bit);
  const fs::path planted = dir_ / "root-only" / "planted";
  giveHomeToNobody();
  for (const std::string transport : {"ipc", "tcp"}) {
    SCOPED_TRACE(transport);
    const fs::path bound = open / (transport + ".endpoint");
    const std::string listen = transport == "ipc" ? "ipc://" + (open / "coordinator.sock").string() : "tcp://127.0.0.1:*";
    // Leaves the cache (cache/<store>/cells/) for root's folder.
    const std::string escape = "cells/../../../root-only/planted";
    // ipc: the worker first, while no socket exists; the impostor binds a second later.
    std::unique_ptr<ChildProcess> worker;
    const auto startWorker = [&](const std::string& endpoint) {
      worker = std::make_unique<ChildProcess>(
          std::vector<std::string>{kBin + "portico-worker", "--connect", endpoint, "--name", "victim", "--cache-dir",
                                   (dir_ / ("cache-" + transport)).string(), "--memory", "256MiB", "--heartbeat-ms",
                                   "250", "--liveness-ms", "1500"},
          (dir_ / ("victim-" + transport + ".log")).string());
    };
    if (transport == "ipc") startWorker(listen);
    std::this_thread::sleep_for(std::chrono::seconds(1));
    std::thread impostor([&] { impostorAsNobody(listen, bound, escape, 6); });
    ASSERT_TRUE(waitUntil([&] { return fs::exists(bound) && !readFile(bound).empty(); }, std::chrono::seconds(5)));
    if (transport == "tcp") startWorker(readFile(bound));
    impostor.join();
    worker->stop();
    const std::string log = readFile(dir_ / ("victim-" + transport + ".log"));
    EXPECT_FALSE(fs::exists(planted)) << "a worker of root wrote where uid nobody's impostor told it\n" << log;
    EXPECT_EQ(log.find("lease 1"), std::string::npos) << log;
    if (transport == "ipc")
      EXPECT_NE(log.find("refused the coordinator at " + listen + ": it is served by uid 65534"), std::string::npos)
          << log;
    else
      EXPECT_NE(log.find("no coordinator key to check it by"), std::string::npos) << log;
    fs::remove(planted);
  }
}

}  // namespace
}  // namespace portico

namespace portico {
namespace {

// uid nobody writes a key folder where root's programs look for their
// per-user keys (PORTICO_KEYS): root's coordinator must not take them, or
// nobody would hold its operator key and shut it down.
TEST_F(LocalUsers, KeysInAFolderAnotherUserMadeAreRefused) {
  giveHomeToNobody();
  const fs::path planted = home_ / "keys-for-root";
  ASSERT_EQ(runCommand(asNobody({program("portico"), "keys", "generate", planted.string()}), dir_ / "keys.log"), 0)
      << readFile(dir_ / "keys.log");
  ::setenv("PORTICO_KEYS", planted.c_str(), 1);
  const fs::path endpointFile = dir_ / "endpoint", log = dir_ / "coordinator.log";
  ChildProcess coordinator({kBin + "portico-coordinator", "--listen", "tcp://127.0.0.1:*", "--db",
                            (dir_ / "jobs.db").string(), "--endpoint-file", endpointFile.string()},
                           log.string());
  waitUntil([&] { return !readFile(endpointFile).empty() || !coordinator.running(); }, std::chrono::seconds(10));
  if (coordinator.running()) {
    // It started with nobody's keys: nobody, holding the operator's, stops it.
    int code = -1;
    std::string endpoint = readFile(endpointFile);
    endpoint.erase(endpoint.find_last_not_of("\n") + 1);
    captureOutput(asNobody({"PORTICO_KEYS=" + planted.string(), program("portico"), "shutdown", "--coordinator",
                            endpoint, "--timeout", "3"}),
                  dir_, "shutdown", &code);
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    EXPECT_NE(readFile(log).find("shutdown requested"), std::string::npos) << readFile(log);
    ADD_FAILURE() << "root's coordinator started with keys uid nobody wrote";
  }
  EXPECT_EQ(coordinator.exitCode(), 1);
  EXPECT_NE(readFile(log).find("key directory " + planted.string() + ": owned by uid 65534, not by uid 0"),
            std::string::npos)
      << readFile(log);
  // Root's worker and client refuse them too.
  int code = -1;
  captureOutput({kBin + "portico", "status", "--coordinator", "tcp://127.0.0.1:9", "--keys", planted.string()}, dir_,
                "status", &code);
  EXPECT_NE(code, 0);
  EXPECT_NE(readFile(dir_ / "status.log").find("owned by uid 65534"), std::string::npos) << readFile(dir_ / "status.log");
}

// Root submits a store in a folder of uid nobody's; nobody then swaps that
// folder for a link to a root-only folder holding another store. The
// coordinator resolved the store's path at submit, and must not follow the
// link when it serves files to a --cache-dir worker.
TEST_F(LocalUsers, AFolderAboveAStoreSwappedForALinkAfterSubmitIsNotFollowed) {
  ASSERT_EQ(generateDemoStore(dir_ / "root-only" / "store", 5), "");
  fs::create_directories(home_ / "project");
  fs::copy(home_ / "store", home_ / "project" / "store", fs::copy_options::recursive);
  giveHomeToNobody();
  LocalCluster cluster(dir_ / "cluster", 0);
  const uint64_t job = cluster.submit(home_ / "project" / "store", dir_ / "swapped.png", 2000, 1);
  ASSERT_EQ(forkAsNobody([&] {
              return ::rename((home_ / "project").c_str(), (home_ / "project.old").c_str()) == 0 &&
                             ::symlink((dir_ / "root-only").c_str(), (home_ / "project").c_str()) == 0
                         ? 0
                         : 1;
            }),
            0);
  cluster.addWorker({"--cache-dir", (dir_ / "cache").string()});
  const auto status = cluster.wait(job);
  const std::string rootsCatalogue = readFile(dir_ / "root-only" / "store" / "scene.db");
  for (const auto& entry : fs::recursive_directory_iterator(dir_ / "cache"))
    EXPECT_FALSE(entry.is_regular_file() && readFile(entry.path()) == rootsCatalogue)
        << entry.path() << ": the coordinator served a root-only store through a link uid nobody made";
  EXPECT_EQ(status.value("state", ""), "failed") << status.dump(2);
  EXPECT_NE(status.value("error", "").find("a symbolic link"), std::string::npos) << status.dump(2);
}

}  // namespace
}  // namespace portico
