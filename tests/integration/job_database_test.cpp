// jobs.db damaged between two runs of the coordinator, through real
// processes: a jobs.db that lost its -wal file, or was truncated to
// nothing, while the photon and batch files of its jobs remain, is refused
// with a message saying what is found and what to do, and nothing is
// deleted; a jobs.db that cannot be used is reported with its real cause.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;

class JobDatabase : public DemoStoreSuite<JobDatabase> {
 protected:
  // A coordinator on dir/jobs.db with a queued job (its emission batches
  // written to jobs.db-batches/), killed with SIGKILL: jobs.db and its WAL
  // hold the job.
  static void leaveAQueuedJob(const fs::path& dir) {
    LocalCluster cluster(dir, 0);
    cluster.submit(store_, dir / "image.exr", 60000, 1);
    cluster.killCoordinator();
  }
  // Starts the coordinator on dir/jobs.db; returns its exit status, its log in dir/restart.log.
  static int startCoordinator(const fs::path& dir) {
    return runCommand({kBin + "portico-coordinator", "--listen", "tcp://127.0.0.1:*", "--db", (dir / "jobs.db").string()},
                      dir / "restart.log");
  }
  static std::vector<fs::path> filesUnder(const fs::path& dir) {
    std::vector<fs::path> files;
    for (const auto& entry : fs::recursive_directory_iterator(dir))
      if (entry.is_regular_file()) files.push_back(entry.path());
    std::sort(files.begin(), files.end());
    return files;
  }
};

// Starting would forget the job and delete its batch files.
TEST_F(JobDatabase, AJobsDbThatLostItsWalOrWasTruncatedIsRefusedAndNothingIsDeleted) {
  for (const std::string loss : {"wal deleted", "truncated to 0"}) {
    SCOPED_TRACE(loss);
    const fs::path dir = dir_ / (loss == "wal deleted" ? "lost-wal" : "truncated");
    leaveAQueuedJob(dir);
    ASSERT_TRUE(fs::exists(dir / "jobs.db-wal"));
    fs::remove(dir / "jobs.db-wal");
    if (loss == "truncated to 0") fs::resize_file(dir / "jobs.db", 0);
    const auto before = filesUnder(dir / "jobs.db-batches");
    ASSERT_FALSE(before.empty());
    EXPECT_EQ(startCoordinator(dir), 1);
    const std::string log = readFile(dir / "restart.log");
    EXPECT_NE(log.find("holds 0 jobs"), std::string::npos) << log;
    EXPECT_NE(log.find("files of 1 jobs it does not have (job 1)"), std::string::npos) << log;
    EXPECT_NE(log.find("Nothing was changed or deleted"), std::string::npos) << log;
    EXPECT_NE(log.find("Restore jobs.db together with its jobs.db-wal"), std::string::npos) << log;
    EXPECT_EQ(filesUnder(dir / "jobs.db-batches"), before);
  }
}

// Only a lock is "in use by another process"; every other failure says its own cause.
TEST_F(JobDatabase, AJobsDbThatCannotBeUsedIsReportedWithItsRealCause) {
  const fs::path garbage = dir_ / "garbage";
  fs::create_directories(garbage);
  std::ofstream(garbage / "jobs.db") << std::string(8192, 'x');
  EXPECT_EQ(startCoordinator(garbage), 1);
  std::string log = readFile(garbage / "restart.log");
  EXPECT_NE(log.find("not a database"), std::string::npos) << log;
  EXPECT_EQ(log.find("in use by another process"), std::string::npos) << log;

  const fs::path folder = dir_ / "folder";
  fs::create_directories(folder / "jobs.db");   // a directory where the file should be
  EXPECT_EQ(startCoordinator(folder), 1);
  log = readFile(folder / "restart.log");
  EXPECT_EQ(log.find("in use by another process"), std::string::npos) << log;
  EXPECT_NE(log.find("jobs.db"), std::string::npos) << log;

  // A second coordinator on a held jobs.db is still told just that.
  const fs::path held = dir_ / "held";
  LocalCluster cluster(held, 0);
  EXPECT_EQ(startCoordinator(held), 1);
  log = readFile(held / "restart.log");
  EXPECT_NE(log.find("in use by another process"), std::string::npos) << log;
}

}  // namespace
}  // namespace portico
