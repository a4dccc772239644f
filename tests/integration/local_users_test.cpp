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
  // A socket in a directory anyone may enter: the peer's uid is what keeps nobody out.
  const fs::path open = dir_ / "open";
  fs::create_directories(open);
  fs::permissions(open, fs::perms::all);
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
