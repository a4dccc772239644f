#include "coordinator/job_store.h"

#include "common/job/worker_tags.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <chrono>
#include <filesystem>
#include <random>

#include <zlib.h>

namespace portico {
namespace {

class JobStoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    path_ = std::filesystem::temp_directory_path() /
            ("portico-jobstore-" + std::to_string(getpid()) + "-" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name() + ".db");
    std::filesystem::remove(path_);
  }
  void TearDown() override {
    for (const char* suffix : {"", "-wal", "-shm"}) {
      std::filesystem::remove(path_.string() + suffix);
      std::filesystem::remove(snapshotPath() + suffix);
    }
    std::filesystem::remove_all(path_.string() + "-photons");
    std::filesystem::remove_all(path_.string() + "-batches");
    std::filesystem::remove_all(snapshotPath() + "-photons");
    std::filesystem::remove_all(snapshotPath() + "-batches");
  }
  // A coordinator holds its jobs.db exclusively: what a store freshly
  // opened on it would read is read from a copy of its files (the database
  // and its write-ahead log; the -batches and -photons files are not needed).
  std::string snapshotPath() const { return path_.string() + ".snapshot"; }
  JobStore openSnapshot() const {
    for (const char* suffix : {"", "-wal"}) {
      std::filesystem::remove(snapshotPath() + suffix);
      if (std::filesystem::exists(path_.string() + suffix))
        std::filesystem::copy_file(path_.string() + suffix, snapshotPath() + suffix);
    }
    return JobStore(snapshotPath());
  }
  std::filesystem::path path_;
};

// Where the last photon batch written lies in its file (batches of the
// photon files start on block boundaries where the file system takes
// direct I/O: append_files.h).
int64_t lastPhotonBatchOffset(JobStore& store) {
  auto& s = store.database().prepare("SELECT file_offset FROM photons ORDER BY id DESC LIMIT 1");
  const int64_t offset = s.step() ? s.columnInt(0) : -1;
  s.reset();
  return offset;
}

// Back to schema 12: no priorities, no worker pools.
void dropVersionFourteenColumns(JobStore& store) { store.database().exec("ALTER TABLE jobs DROP COLUMN owner"); }
void dropVersionThirteenColumns(JobStore& store) {
  dropVersionFourteenColumns(store);
  store.database().exec("ALTER TABLE jobs DROP COLUMN priority; ALTER TABLE jobs DROP COLUMN required_tags");
}

TEST_F(JobStoreTest, CreatesSchemaAtCurrentVersionInWalMode) {
  JobStore store(path_.string());
  EXPECT_EQ(store.database().userVersion(), JobStore::kSchemaVersion);
  auto& s = store.database().prepare("PRAGMA journal_mode");
  ASSERT_TRUE(s.step());
  EXPECT_EQ(s.columnText(0), "wal");
  s.reset();
}

TEST_F(JobStoreTest, RefusesANewerSchema) {
  { JobStore store(path_.string()); store.database().setUserVersion(JobStore::kSchemaVersion + 1); }
  EXPECT_THROW(JobStore{path_.string()}, std::runtime_error);
}

// One coordinator per jobs.db: a second store on a database that a live
// one holds is refused at once, naming the file, and the first one goes on.
TEST_F(JobStoreTest, ASecondStoreOnAHeldDatabaseIsRefusedAtOnce) {
  JobStore store(path_.string());
  const uint64_t job = store.createJob("spec", 1);
  const auto started = std::chrono::steady_clock::now();
  try {
    JobStore second(path_.string());
    FAIL() << "a second store opened a held jobs.db";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path_.string() + ": in use by another process"), std::string::npos)
        << e.what();
  }
  EXPECT_LT(std::chrono::steady_clock::now() - started, std::chrono::seconds(2));
  store.addBatch(job, 1, 0, BatchKind::Rays, 5, "rays");
  EXPECT_EQ(store.pendingCells(10).size(), 1u);
}

// The coordinator's rounds (one commit for all it handled) nest each
// handler's transaction as a savepoint: a rejected Result is undone alone,
// and the unleased-work cache follows the partial rollback, which SQLite's
// rollback hook does not report.
TEST_F(JobStoreTest, ANestedTransactionRollsBackAloneAndTheCacheFollows) {
  JobStore store(path_.string());
  const uint64_t job = store.createJob("spec", 1);
  {
    sql::Transaction round(store.database());
    store.addBatch(job, 3, 0, BatchKind::Rays, 100, "kept");
    {
      sql::Transaction rejected(store.database());
      store.addBatch(job, 3, 0, BatchKind::Rays, 40, "undone");
      store.addBatch(job, 5, 0, BatchKind::Rays, 70, "undone too");
      EXPECT_EQ(store.pendingCells(10).size(), 2u);
    }   // destroyed uncommitted: a savepoint rolled back
    auto pending = store.pendingCells(10);
    ASSERT_EQ(pending.size(), 1u);
    EXPECT_EQ(pending[0].work, 100);
    {
      sql::Transaction accepted(store.database());
      store.addBatch(job, 4, 0, BatchKind::Rays, 10, "released");
      accepted.commit();   // into the round, not yet durable
    }
    EXPECT_TRUE(store.database().inTransaction());
    round.commit();
  }
  EXPECT_FALSE(store.database().inTransaction());
  {
    sql::Transaction round(store.database());
    store.addBatch(job, 6, 0, BatchKind::Rays, 999, "lost with its round");
    sql::Transaction inner(store.database());
    inner.commit();
  }   // the round rolls back, taking the committed savepoint with it
  JobStore reopened = openSnapshot();
  auto pending = reopened.pendingCells(10);
  ASSERT_EQ(pending.size(), 2u);
  EXPECT_EQ(pending[0].cell, 3u);
  EXPECT_EQ(pending[0].work, 100);
  EXPECT_EQ(pending[1].cell, 4u);
  EXPECT_EQ(store.pendingCells(10).size(), 2u);   // the first store's cache agrees
}

// The end of a photon pass: one lease carries several cells' batches, and
// completes or goes back to the queue as one.
TEST_F(JobStoreTest, ALeaseOfSeveralCellsCompletesAndRequeuesAsOne) {
  JobStore store(path_.string());
  const uint64_t job = store.createJob("spec", 1);
  store.addBatch(job, 3, 0, BatchKind::Rays, 10, "three");
  store.addBatch(job, 4, 0, BatchKind::Rays, 20, "four a");
  store.addBatch(job, 4, 0, BatchKind::Rays, 30, "four b");
  std::vector<QueuedBatch> batches, more;
  const uint64_t lease = store.openLease({job, 3, 0, 10}, "worker-a", 100, 1, batches).id;
  EXPECT_EQ(store.addToLease(lease, {job, 4, 0, 50}, 25, more), 20);   // up to the work asked for
  ASSERT_EQ(more.size(), 1u);
  EXPECT_EQ(more[0].payload, "four a");
  auto pending = store.pendingCells(10);
  ASSERT_EQ(pending.size(), 1u);
  EXPECT_EQ(pending[0].cell, 4u);
  EXPECT_EQ(pending[0].work, 30);
  store.requeueLease(lease);
  EXPECT_EQ(store.pendingCells(10).size(), 2u);
  EXPECT_EQ(store.remainingWork(job, 0), 3);

  const uint64_t second = store.openLease({job, 4, 0, 50}, "worker-b", 100, 2, batches).id;
  EXPECT_EQ(store.addToLease(second, {job, 3, 0, 10}, 100, more), 10);
  EXPECT_EQ(store.addToLease(second, {job, 5, 0, 0}, 100, more), 0);   // nothing there
  EXPECT_TRUE(store.pendingCells(10).empty());
  store.completeLease(second);
  EXPECT_EQ(store.remainingWork(job, 0), 0);
}

TEST_F(JobStoreTest, LeasesTakeBatchesUpToTheWorkLimitAndCompleteOrRequeue) {
  JobStore store(path_.string());
  const uint64_t job = store.createJob("spec", 1);
  for (int i = 0; i < 5; ++i) store.addBatch(job, 3, 0, BatchKind::Rays, 100, "payload" + std::to_string(i));
  store.addBatch(job, 4, 0, BatchKind::Rays, 50, "other");
  auto pending = store.pendingCells(10);
  ASSERT_EQ(pending.size(), 2u);
  EXPECT_EQ(pending[0].cell, 3u);   // most work first
  EXPECT_EQ(pending[0].work, 500);

  std::vector<QueuedBatch> batches;
  const uint64_t lease = store.openLease(pending[0], "worker-a", 250, 2, batches).id;
  ASSERT_NE(lease, 0u);
  ASSERT_EQ(batches.size(), 2u);
  EXPECT_EQ(batches[0].payload, "payload0");
  EXPECT_EQ(store.openLeaseCount(job), 1);
  EXPECT_EQ(store.pendingCells(10)[0].work, 300);   // leased batches are not pending

  store.requeueLease(lease);
  EXPECT_FALSE(store.lease(lease));   // a closed lease leaves no row: its Result is dropped
  EXPECT_EQ(store.openLeaseCount(job), 0);
  EXPECT_EQ(store.pendingCells(10)[0].work, 500);

  const uint64_t second = store.openLease(store.pendingCells(10)[0], "worker-b", 1000, 3, batches).id;
  EXPECT_EQ(batches.size(), 5u);
  store.completeLease(second);
  EXPECT_FALSE(store.lease(second));
  // Ids never repeat, though closed leases leave no row: a late Result must
  // not pass for a new lease's.
  const uint64_t third = store.openLease(store.pendingCells(10)[0], "worker-b", 1000, 4, batches).id;
  EXPECT_GT(third, second);
  store.requeueLease(third);
  EXPECT_EQ(store.remainingWork(job, 0), 1);   // cell 4's batch
  EXPECT_TRUE(store.hasRemainingWork(job, 0));
  EXPECT_FALSE(store.hasRemainingWork(job, 1));
  EXPECT_EQ(store.queuedRays(job, 0), 50);
}

TEST_F(JobStoreTest, RestartRequeuesOpenLeases) {
  uint64_t lease;
  {
    JobStore store(path_.string());
    const uint64_t job = store.createJob("spec", 1);
    store.addBatch(job, 1, 0, BatchKind::Emit, 10, "x");
    std::vector<QueuedBatch> batches;
    lease = store.openLease(store.pendingCells(1)[0], "gone", 100, 1, batches).id;
  }
  JobStore reopened(path_.string());
  EXPECT_EQ(reopened.requeueAllOpenLeases(), 1);
  EXPECT_FALSE(reopened.lease(lease));
  EXPECT_EQ(reopened.pendingCells(1).size(), 1u);
  // The coordinator, not the cell, was lost: the next lease is still a first attempt.
  std::vector<QueuedBatch> batches;
  const LeaseRecord next = reopened.openLease(reopened.pendingCells(1)[0], "next", 100, 2, batches);
  EXPECT_EQ(next.attempt, 1u);
  EXPECT_GT(next.id, lease);   // the requeued lease's id is not given again
}

TEST_F(JobStoreTest, LeasesLostWithTheirWorkerCountAsAttemptsOfTheirBatches) {
  JobStore store(path_.string());
  const uint64_t job = store.createJob("spec", 1);
  store.addBatch(job, 7, 0, BatchKind::Rays, 100, "a");
  store.addBatch(job, 7, 0, BatchKind::Rays, 100, "b");
  std::vector<QueuedBatch> batches;
  LeaseRecord first = store.openLease(store.pendingCells(1)[0], "w1", 100, 1, batches);   // batch a only
  EXPECT_EQ(first.attempt, 1u);
  EXPECT_EQ(store.lease(first.id)->attempt, 1u);
  store.requeueLease(first.id, /*lost=*/true);
  LeaseRecord second = store.openLease(store.pendingCells(1)[0], "w2", 1000, 2, batches);   // a and b
  ASSERT_EQ(batches.size(), 2u);
  EXPECT_EQ(batches[0].attempts, 1u);
  EXPECT_EQ(batches[1].attempts, 0u);
  EXPECT_EQ(second.attempt, 2u);   // 1 + the most a batch was lost
  EXPECT_EQ(second.cell, 7u);
  EXPECT_EQ(second.worker, "w2");
  EXPECT_EQ(store.lease(second.id)->attempt, 2u);
  // A failure the worker reported is not a lost lease.
  store.requeueLease(second.id);
  EXPECT_EQ(store.openLease(store.pendingCells(1)[0], "w3", 1000, 3, batches).attempt, 2u);
}

// Back to version 5's jobs table: no photon-pass reuse.
void dropVersionSixColumns(JobStore& store) {
  store.database().exec("DROP INDEX jobs_by_photon_key");
  for (const char* column : {"photon_key", "photon_source", "photons_complete"})
    store.database().exec(std::string("ALTER TABLE jobs DROP COLUMN ") + column);
}

TEST_F(JobStoreTest, APhotonPassIsOfferedOnceCompleteWithItsFileWholeAndNoLongerOnceRestarted) {
  JobStore store(path_.string());
  const uint64_t lender = store.createJob("spec", 1);
  store.setPhotonPass(lender, "key", 0);
  store.addPhotons(lender, 3, 10, std::string(160, 'p'));
  EXPECT_EQ(store.reusablePhotonPass("key"), std::nullopt);   // its pass is not complete
  store.markPhotonPassComplete(lender);
  store.setJobState(lender, JobState::Render, 2);
  EXPECT_EQ(store.reusablePhotonPass("key"), lender);
  EXPECT_EQ(store.reusablePhotonPass("other key"), std::nullopt);
  EXPECT_EQ(store.reusablePhotonPass(""), std::nullopt);
  const uint64_t borrower = store.createJob("spec", 3);
  store.setPhotonPass(borrower, "key", lender);
  EXPECT_EQ(store.job(borrower)->photonJob(), lender);
  store.markPhotonPassComplete(borrower);
  store.setJobState(borrower, JobState::Done, 4);
  EXPECT_EQ(store.reusablePhotonPass("key"), lender);   // a borrower lends nothing
  // A file cut short is not offered.
  std::filesystem::resize_file(store.photonFile(lender), 100);
  EXPECT_EQ(store.reusablePhotonPass("key"), std::nullopt);
  // A borrower that runs its pass again runs its own.
  store.restartJob(borrower, 5);
  EXPECT_EQ(store.job(borrower)->photonJob(), borrower);
  EXPECT_FALSE(store.job(borrower)->photonsComplete);
  store.withdrawPhotonPass(lender);
  EXPECT_EQ(store.job(lender)->photonKey, "");
}

TEST_F(JobStoreTest, MigratesAVersionOneDatabaseKeepingItsQueue) {
  {
    JobStore store(path_.string());
    store.createJob("spec", 1);
    // Back to version 1's shape: no attempts column, ray and photon batches as blobs.
    for (const char* column : {"attempts", "file_segment", "file_offset", "file_size", "file_crc"})
      store.database().exec(std::string("ALTER TABLE batches DROP COLUMN ") + column);
    store.database().exec("INSERT INTO batches(job, cell, phase, kind, work, payload) VALUES (1, 2, 0, 0, 40, 'queued')");
    for (const char* column : {"file_offset", "file_size", "file_crc"})
      store.database().exec(std::string("ALTER TABLE photons DROP COLUMN ") + column);
    store.database().exec("INSERT INTO photons(job, cell, count, payload) VALUES (1, 7, 1, x'0102')");
    store.database().exec("ALTER TABLE jobs DROP COLUMN photon_record_bytes");
    store.database().exec("DROP TABLE render_progress; DROP TABLE render_passes");   // schema 7
    store.database().exec("DROP TABLE lease_log");   // schema 8
    dropVersionSixColumns(store);
    store.database().exec("ALTER TABLE jobs DROP COLUMN photon_region_end");   // schema 11
    store.database().exec("DROP TABLE job_sensors");   // schema 12
    dropVersionThirteenColumns(store);
    store.database().setUserVersion(1);
  }
  JobStore migrated(path_.string());
  EXPECT_EQ(migrated.database().userVersion(), JobStore::kSchemaVersion);
  std::vector<QueuedBatch> batches;
  const LeaseRecord lease = migrated.openLease(migrated.pendingCells(1)[0], "w", 100, 2, batches);
  ASSERT_EQ(batches.size(), 1u);
  EXPECT_EQ(batches[0].payload, "queued");
  EXPECT_EQ(lease.attempt, 1u);
  EXPECT_EQ(migrated.photonBatches(1, 7), std::vector<std::string>{std::string("\x01\x02")});
}

TEST_F(JobStoreTest, PendingCellsComeByPriorityThenAgeAndOnlyOfJobsTheAskerMayTake) {
  JobStore store(path_.string());
  const uint64_t oldest = store.createJob("spec", 1), urgent = store.createJob("spec", 2),
                 pooled = store.createJob("spec", 3);
  store.addBatch(oldest, 1, 0, BatchKind::Rays, 500, "a");
  store.addBatch(urgent, 2, 0, BatchKind::Rays, 10, "b");
  store.addBatch(pooled, 3, 0, BatchKind::Rays, 20, "c");
  const auto jobsOf = [](const std::vector<PendingCell>& cells) {
    std::vector<uint64_t> jobs;
    for (const PendingCell& c : cells) jobs.push_back(c.job);
    return jobs;
  };
  // Equal priorities: the oldest job first, as ever.
  EXPECT_EQ(jobsOf(store.pendingCells(10)), (std::vector<uint64_t>{oldest, urgent, pooled}));
  store.setPriority(urgent, 5);
  store.setPriority(pooled, -3);
  store.setRequiredTags(pooled, {"bigmem", "gpu"});
  EXPECT_EQ(jobsOf(store.pendingCells(10)), (std::vector<uint64_t>{urgent, oldest, pooled}));
  // A worker without both tags is not offered the pooled job's cells.
  const auto withTags = [](std::vector<std::string> tags) {
    return [tags](const std::vector<std::string>& required) { return hasAllTags(tags, required); };
  };
  EXPECT_EQ(jobsOf(store.pendingCells(10, withTags({"gpu"}))), (std::vector<uint64_t>{urgent, oldest}));
  EXPECT_EQ(jobsOf(store.pendingCells(10, withTags({"bigmem", "gpu", "x"}))),
            (std::vector<uint64_t>{urgent, oldest, pooled}));
  // Kept in jobs.db: a coordinator restarted on it schedules alike.
  JobStore reopened = openSnapshot();
  EXPECT_EQ(jobsOf(reopened.pendingCells(10)), (std::vector<uint64_t>{urgent, oldest, pooled}));
  EXPECT_EQ(reopened.job(urgent)->priority, 5);
  EXPECT_EQ(reopened.job(pooled)->requiredTags, (std::vector<std::string>{"bigmem", "gpu"}));
  EXPECT_TRUE(reopened.job(oldest)->requiredTags.empty());
}

TEST_F(JobStoreTest, ADatabaseOfSchemaTwelveMigratesWithEveryJobAtPriorityZeroForAnyWorker) {
  {
    JobStore store(path_.string());
    store.createJob("spec", 1);
    store.createJob("spec", 2);
    store.addBatch(2, 4, 0, BatchKind::Rays, 900, "second");
    store.addBatch(1, 3, 0, BatchKind::Rays, 100, "first");
    dropVersionThirteenColumns(store);
    store.database().setUserVersion(12);
  }
  JobStore migrated(path_.string());
  EXPECT_EQ(migrated.database().userVersion(), JobStore::kSchemaVersion);
  EXPECT_EQ(migrated.job(1)->priority, 0);
  EXPECT_TRUE(migrated.job(2)->requiredTags.empty());
  const auto pending = migrated.pendingCells(10, [](const std::vector<std::string>& required) { return required.empty(); });
  ASSERT_EQ(pending.size(), 2u);
  EXPECT_EQ(pending[0].job, 1u);   // the oldest first, as before priorities
  EXPECT_EQ(pending[1].job, 2u);
}

TEST_F(JobStoreTest, EachJobKeepsItsOwnerAndADatabaseOfSchemaThirteenMigratesWithNone) {
  {
    JobStore store(path_.string());
    store.createJob("spec", 1);
    dropVersionFourteenColumns(store);
    store.database().setUserVersion(13);
  }
  JobStore migrated(path_.string());
  EXPECT_EQ(migrated.database().userVersion(), JobStore::kSchemaVersion);
  EXPECT_EQ(migrated.job(1)->owner, "");   // submitted before owners were kept
  const uint64_t job = migrated.createJob("spec", 2);
  migrated.setOwner(job, "key:abc");
  EXPECT_EQ(migrated.job(job)->owner, "key:abc");
  EXPECT_EQ(openSnapshot().job(job)->owner, "key:abc");
  EXPECT_EQ(migrated.jobs(false).back().owner, "key:abc");
}

TEST_F(JobStoreTest, PendingCellsStayTrueToTheBatchesTableThroughLeasesRequeuesAndRollbacks) {
  // pendingCells() ranks work it keeps in memory beside the table; a store
  // reopened on the same file ranks it from the table alone. After every
  // step of a random run of queueing, leasing, completing, requeueing and
  // rolled-back transactions, both must agree.
  JobStore store(path_.string());
  const uint64_t first = store.createJob("a", 1), second = store.createJob("b", 2);
  std::mt19937 random(11);
  std::vector<uint64_t> open;
  const auto expectSameAsFromTheTable = [&](int step) {
    JobStore fresh = openSnapshot();
    const auto a = store.pendingCells(1000), b = fresh.pendingCells(1000);
    ASSERT_EQ(a.size(), b.size()) << "step " << step;
    for (size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(a[i].job, b[i].job) << "step " << step;
      EXPECT_EQ(a[i].cell, b[i].cell) << "step " << step;
      EXPECT_EQ(a[i].phase, b[i].phase) << "step " << step;
      EXPECT_EQ(a[i].work, b[i].work) << "step " << step;
    }
  };
  for (int step = 0; step < 300; ++step) {
    const int action = int(random() % 6);
    const uint64_t job = random() % 2 ? first : second;
    if (action <= 1) {
      store.addBatch(job, uint32_t(random() % 7), 0, BatchKind::Rays, int64_t(1 + random() % 50), "rays");
    } else if (action == 2) {
      const auto cells = store.pendingCells(8);
      if (cells.empty()) continue;
      std::vector<QueuedBatch> batches;
      const LeaseRecord lease =
          store.openLease(cells[random() % cells.size()], "w", int64_t(1 + random() % 80), step, batches);
      if (lease.id) open.push_back(lease.id);
    } else if (action == 3 && !open.empty()) {
      store.completeLease(open.back());
      open.pop_back();
    } else if (action == 4 && !open.empty()) {
      store.requeueLease(open.front(), random() % 2 == 0);
      open.erase(open.begin());
    } else if (action == 5) {
      // A Result that is rejected halfway: nothing of it stays.
      sql::Transaction tx(store.database());
      store.addBatch(job, uint32_t(random() % 7), 0, BatchKind::Rays, 1000, "rolled back");
      const auto cells = store.pendingCells(8);
      std::vector<QueuedBatch> batches;
      if (!cells.empty()) store.openLease(cells.front(), "w", 30, step, batches);
    }
    if (step % 10 == 0) expectSameAsFromTheTable(step);
  }
  expectSameAsFromTheTable(300);
}

TEST_F(JobStoreTest, RestartingAJobDropsItsWorkPhotonsFilmAndCountersButCountsTheRestarts) {
  JobStore store(path_.string());
  const uint64_t job = store.createJob("spec", 1), other = store.createJob("other", 1);
  for (uint64_t j : {job, other}) {
    store.addBatch(j, 1, 0, BatchKind::Rays, 10, "rays");
    store.addPhotons(j, 1, 1, std::string(24, 'p'));
    store.addFilm(j, {{0, {1, 2, 3}}}, 4);
    store.addCounter(j, "photons.emitted", 5);
  }
  store.setJobState(job, JobState::Render, 2);
  for (int restart = 1; restart <= 2; ++restart) {
    store.restartJob(job, 3);
    EXPECT_EQ(store.job(job)->state, JobState::Photons);
    EXPECT_EQ(store.remainingWork(job, 0), 0);
    EXPECT_TRUE(store.photonBatches(job, 1).empty());
    EXPECT_EQ(store.film(job, 4)[0].r, 0);
    const auto counters = store.counters(job);
    EXPECT_EQ(counters.count("photons.emitted"), 0u);
    EXPECT_EQ(counters.at(JobStore::kPhotonPassRestarts), restart);
  }
  // New photons start the file afresh; the other job is untouched.
  store.addPhotons(job, 1, 1, std::string(24, 'n'));
  EXPECT_EQ(store.photonBatches(job, 1), std::vector<std::string>{std::string(24, 'n')});
  EXPECT_EQ(lastPhotonBatchOffset(store), 0);
  EXPECT_EQ(store.photonBatches(other, 1).size(), 1u);
  EXPECT_EQ(store.remainingWork(other, 0), 1);
  EXPECT_EQ(store.counters(other).at("photons.emitted"), 5);
}

TEST_F(JobStoreTest, FilmChunksAccumulate) {
  JobStore store(path_.string());
  const uint64_t job = store.createJob("spec", 1);
  const uint64_t pixels = JobStore::kFilmChunkPixels * 2 + 10;
  store.addFilm(job, {{0, {1, 2, 3}}, {pixels - 1, {5, 5, 5}}}, pixels);
  store.addFilm(job, {{0, {10, 20, 30}}}, pixels);
  const auto film = store.film(job, pixels);
  EXPECT_EQ(film[0].r, 11);
  EXPECT_EQ(film[0].b, 33);
  EXPECT_EQ(film[pixels - 1].g, 5);
  EXPECT_EQ(film[1].r, 0);
  EXPECT_THROW(store.addFilm(job, {{uint32_t(pixels), {1, 1, 1}}}, pixels), std::runtime_error);
}

TEST_F(JobStoreTest, CountersAdd) {
  JobStore store(path_.string());
  const uint64_t job = store.createJob("spec", 1);
  store.addCounter(job, "photons.emitted", 5);
  store.addCounter(job, "photons.emitted", 7);
  EXPECT_EQ(store.counters(job).at("photons.emitted"), 12);
}

TEST_F(JobStoreTest, RaisedCountersKeepTheirPeakAndTheLeaseLogKeepsEachLease) {
  JobStore store(path_.string());
  const uint64_t job = store.createJob("spec", 1);
  store.raiseCounter(job, "memory.peak", 300);
  store.raiseCounter(job, "memory.peak", 200);
  store.raiseCounter(job, "memory.peak", 500);
  EXPECT_EQ(store.counters(job).at("memory.peak"), 500);
  LeaseLogEntry first{job, 7, 0, 3, 2, 1500, "w0", 10, 40, 25000, 4000, 1, 20000, 21000, 3000, true, {{11, 200}, {4, 50}}};
  LeaseLogEntry second{job, 8, 1, 5, 0, 900, "w1", 20, 30, 9000, 0, 0, 0};   // CPU, more cells not recorded
  store.logLease(second);
  store.logLease(first);
  const auto log = store.leaseLog(job);
  ASSERT_EQ(log.size(), 2u);
  EXPECT_EQ(log[0].lease, 8u);   // in the order their Results were applied
  EXPECT_EQ(log[1].cell, 3u);
  EXPECT_EQ(log[1].moreCells, 2u);
  EXPECT_EQ(log[1].work, 1500);
  EXPECT_EQ(log[1].worker, "w0");
  EXPECT_EQ(log[1].leaseMicros, 25000);
  EXPECT_EQ(log[1].loadMicros, 4000);
  EXPECT_EQ(log[1].trianglesLoaded, 20000);
  EXPECT_EQ(log[1].cpuMicros, 21000);
  EXPECT_EQ(log[1].runQueueMicros, 3000);
  EXPECT_TRUE(log[1].moreCellsLogged);
  EXPECT_EQ(log[1].moreCellWork, (std::vector<std::pair<uint32_t, int64_t>>{{11, 200}, {4, 50}}));
  EXPECT_EQ(log[0].cpuMicros, -1);
  EXPECT_EQ(log[0].runQueueMicros, -1);
  EXPECT_FALSE(log[0].moreCellsLogged);
  EXPECT_TRUE(store.leaseLog(job + 1).empty());
}

TEST_F(JobStoreTest, ALeaseLogOfSchemaEightReadsWithItsCpuUnrecorded) {
  {
    JobStore store(path_.string());
    store.createJob("spec", 1);
    store.database().exec(
        "ALTER TABLE lease_log DROP COLUMN cpu_us; ALTER TABLE lease_log DROP COLUMN run_queue_us; "
        "ALTER TABLE lease_log DROP COLUMN more_cell_work");
    store.database().exec(
        "INSERT INTO lease_log(job, lease, phase, cell, more_cells, work, worker, sent_ms, result_ms, lease_us, "
        "load_us, cells_loaded, triangles_loaded) VALUES (1, 4, 0, 2, 0, 800, 'w0', 5, 9, 4000, 0, 0, 0)");
    store.database().exec("ALTER TABLE jobs DROP COLUMN photon_region_end");   // schema 11
    store.database().exec("DROP TABLE job_sensors");   // schema 12
    dropVersionThirteenColumns(store);
    store.database().setUserVersion(8);
  }
  JobStore migrated(path_.string());
  EXPECT_EQ(migrated.database().userVersion(), JobStore::kSchemaVersion);
  const auto log = migrated.leaseLog(1);
  ASSERT_EQ(log.size(), 1u);
  EXPECT_EQ(log[0].leaseMicros, 4000);
  EXPECT_EQ(log[0].cpuMicros, -1);
  EXPECT_EQ(log[0].runQueueMicros, -1);
  EXPECT_FALSE(log[0].moreCellsLogged);   // counted, not named
}

}  // namespace
}  // namespace portico

#include "common/transport/photon_record.h"

namespace portico {
namespace {

TEST_F(JobStoreTest, PhotonTablesRoundTripThroughDiskWithoutLoss) {
  // Records written batch by batch come back byte for byte, after the
  // database is closed and reopened, in the order they were appended.
  const PhotonFrame frame(Bounds3(Vec3(0.0f), Vec3(1100.0f, 10.0f, 1.0f)), 0.5f, 0.001f);
  std::vector<std::string> written;
  {
    JobStore store(path_.string());
    const uint64_t job = store.createJob("spec", 1);
    for (int batch = 0; batch < 5; ++batch) {
      std::vector<StoredPhoton> photons(1000 + batch);
      for (size_t i = 0; i < photons.size(); ++i) {
        photons[i].position = Vec3(float(i), float(batch), 0.5f);
        photons[i].direction = normalize(Vec3(1, -1, float(i % 7)));
        photons[i].power = Vec3(0.001f * (i + 1), 0.002f, 0.0005f);
        photons[i].bounce = static_cast<uint16_t>(i % 4);
      }
      written.push_back(packRecords(photons, frame));
      store.addPhotons(job, 3, int64_t(photons.size()), written.back());
    }
    store.addPhotons(job, 4, 1, packRecords({StoredPhoton{}}, frame));
  }
  JobStore reopened(path_.string());
  const auto read = reopened.photonBatches(1, 3);
  ASSERT_EQ(read.size(), written.size());
  for (size_t i = 0; i < read.size(); ++i) EXPECT_EQ(read[i], written[i]) << i;
  std::vector<StoredPhoton> decoded;
  for (const std::string& blob : read) unpackRecords(blob.data(), blob.size(), frame, true, decoded);
  EXPECT_EQ(decoded.size(), 1000u + 1001 + 1002 + 1003 + 1004);
  EXPECT_EQ(reopened.photonBatches(1, 4).size(), 1u);
  EXPECT_TRUE(reopened.photonBatches(1, 5).empty());
}

TEST_F(JobStoreTest, PhotonBatchesLiveInAFileBesideTheDatabaseAndOnlyCommittedOnesCount) {
  const std::string first(240, 'a'), lost(480, 'b'), second(72, 'c');
  std::filesystem::path file;
  uintmax_t withLost = 0;
  {
    JobStore store(path_.string());
    const uint64_t job = store.createJob("spec", 1);
    file = store.photonFile(job);
    store.addPhotons(job, 0, 10, first);
    const uintmax_t withFirst = std::filesystem::file_size(file);
    EXPECT_GE(withFirst, first.size());
    {
      // A Result whose transaction rolls back: its bytes are written, no row.
      sql::Transaction tx(store.database());
      store.addPhotons(job, 0, 20, lost);
    }
    withLost = std::filesystem::file_size(file);
    EXPECT_GE(withLost, withFirst + lost.size());
    EXPECT_EQ(store.photonBatches(job, 0), std::vector<std::string>{first});
  }
  // Not in jobs.db: the database holds where the batch lies, not its bytes.
  {
    JobStore reopened(path_.string());
    auto& s = reopened.database().prepare("SELECT SUM(LENGTH(payload)) FROM photons");
    ASSERT_TRUE(s.step());
    EXPECT_EQ(s.columnInt(0), 0);
    s.reset();
    // A new coordinator writes over the bytes of the uncommitted batch.
    reopened.addPhotons(1, 0, 3, second);
    EXPECT_GE(lastPhotonBatchOffset(reopened), int64_t(first.size()));
    EXPECT_LT(lastPhotonBatchOffset(reopened) + int64_t(second.size()), int64_t(withLost));
    EXPECT_LE(std::filesystem::file_size(file), withLost);
    EXPECT_EQ(reopened.photonBatches(1, 0), (std::vector<std::string>{first, second}));
  }
}

TEST_F(JobStoreTest, ADamagedPhotonFileIsReportedNamingTheFile) {
  std::filesystem::path file;
  {
    JobStore store(path_.string());
    const uint64_t job = store.createJob("spec", 1);
    file = store.photonFile(job);
    store.addPhotons(job, 2, 10, std::string(240, 'x'));
  }
  {
    std::FILE* f = std::fopen(file.c_str(), "r+b");
    ASSERT_NE(f, nullptr);
    std::fseek(f, 100, SEEK_SET);
    std::fputc('y', f);
    std::fclose(f);
  }
  JobStore reopened(path_.string());
  try {
    reopened.photonBatches(1, 2);
    FAIL() << "a damaged batch was returned";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("damaged"), std::string::npos) << e.what();
  }
  // The database is still usable.
  EXPECT_TRUE(reopened.photonBatches(1, 3).empty());
}

TEST_F(JobStoreTest, PhotonBlobsOfAnEarlierSchemaAreStillRead) {
  JobStore store(path_.string());
  const uint64_t job = store.createJob("spec", 1);
  // A row as schema version 2 wrote it: the payload in jobs.db.
  auto& s = store.database().prepare("INSERT INTO photons(job, cell, count, payload) VALUES (?, 5, 1, ?)");
  const std::string old(24, 'o');
  s.bind(1, int64_t(job)).bindBlob(2, old.data(), old.size());
  s.run();
  store.addPhotons(job, 5, 1, std::string(24, 'n'));
  EXPECT_EQ(store.photonBatches(job, 5), (std::vector<std::string>{old, std::string(24, 'n')}));
}

namespace {
void overwriteByte(const std::filesystem::path& file, long offset) {
  std::FILE* f = std::fopen(file.c_str(), "r+b");
  ASSERT_NE(f, nullptr) << file;
  std::fseek(f, offset, SEEK_SET);
  const int old = std::fgetc(f);
  std::fseek(f, offset, SEEK_SET);
  std::fputc(old ^ 0x5a, f);
  std::fclose(f);
}
}  // namespace

TEST_F(JobStoreTest, LargePhotonBatchesAndSmallOnesBetweenThemRoundTripAndDamageShows) {
  // Batches of kDirectLeastBytes and more take O_DIRECT where the file
  // system has it, small ones the page cache, in one file: each comes back
  // byte for byte, also after a reopen and a rolled-back large batch, and a
  // byte changed inside a large batch is caught.
  const auto pattern = [](size_t size, char seed) {
    std::string bytes(size, '\0');
    for (size_t i = 0; i < size; ++i) bytes[i] = char(seed + char(i * 7 % 251));
    return bytes;
  };
  const size_t large = size_t(AppendFiles::kDirectLeastBytes);
  const std::vector<std::string> batches{pattern(large + 16, 'a'), pattern(48, 'b'), pattern(3 * large, 'c'),
                                         pattern(large - 16, 'd'), pattern(large, 'e')};
  std::filesystem::path file;
  {
    JobStore store(path_.string());
    const uint64_t job = store.createJob("spec", 1);
    file = store.photonFile(job);
    for (const std::string& batch : batches) store.addPhotons(job, 7, int64_t(batch.size() / 16), batch);
    EXPECT_EQ(store.photonBatches(job, 7), batches);
    {
      sql::Transaction tx(store.database());   // rolled back: bytes, no row
      store.addPhotons(job, 7, 1, pattern(2 * large, 'x'));
    }
  }
  int64_t lastOffset = 0;
  {
    JobStore reopened(path_.string());
    reopened.addPhotons(1, 7, 1, pattern(large, 'f'));
    lastOffset = lastPhotonBatchOffset(reopened);
    std::vector<std::string> expected = batches;
    expected.push_back(pattern(large, 'f'));
    EXPECT_EQ(reopened.photonBatches(1, 7), expected);
  }
  overwriteByte(file, long(lastOffset + 1000));
  JobStore damaged(path_.string());
  EXPECT_THROW(damaged.photonBatches(1, 7), DamagedFileError);
}


TEST_F(JobStoreTest, RayBatchesLiveInFilesBesideTheDatabaseAndOnlyCommittedOnesCount) {
  const std::string first(300, 'a'), lost(500, 'b'), second(70, 'c');
  std::filesystem::path file;
  {
    JobStore store(path_.string());
    const uint64_t job = store.createJob("spec", 1);
    file = store.batchFile(job, 0);
    store.addBatch(job, 3, 0, BatchKind::Rays, 10, first);
    {
      // A Result whose transaction rolls back: its bytes are written, no row.
      sql::Transaction tx(store.database());
      store.addBatch(job, 3, 0, BatchKind::Rays, 20, lost);
    }
    EXPECT_EQ(std::filesystem::file_size(file), first.size() + lost.size());
    auto& s = store.database().prepare("SELECT SUM(LENGTH(payload)), COUNT(*) FROM batches");
    ASSERT_TRUE(s.step());
    EXPECT_EQ(s.columnInt(0), 0);   // where the bytes lie, not the bytes
    EXPECT_EQ(s.columnInt(1), 1);
    s.reset();
  }
  JobStore reopened(path_.string());
  // A new coordinator writes over the bytes of the uncommitted batch.
  reopened.addBatch(1, 3, 0, BatchKind::Rays, 5, second);
  EXPECT_EQ(std::filesystem::file_size(file), first.size() + second.size());
  std::vector<QueuedBatch> batches;
  const LeaseRecord lease = reopened.openLease(reopened.pendingCells(1)[0], "w", 1000, 2, batches);
  ASSERT_EQ(batches.size(), 2u);
  EXPECT_EQ(batches[0].payload, first);
  EXPECT_EQ(batches[1].payload, second);
  EXPECT_EQ(lease.cell, 3u);
}

TEST_F(JobStoreTest, ConsumedBatchSegmentsAndAnEndedJobsFilesAreDeleted) {
  // Segments of 1000 bytes: the second batch fills the first segment.
  JobStore store(path_.string(), 1000);
  const uint64_t job = store.createJob("spec", 1);
  store.addBatch(job, 1, 0, BatchKind::Rays, 10, std::string(600, '1'));
  store.addBatch(job, 1, 0, BatchKind::Rays, 10, std::string(600, '2'));
  store.addBatch(job, 2, 0, BatchKind::Rays, 10, std::string(600, '3'));
  EXPECT_TRUE(std::filesystem::exists(store.batchFile(job, 0)));
  EXPECT_EQ(std::filesystem::file_size(store.batchFile(job, 1)), 600u);
  store.reclaimBatchFiles();
  EXPECT_TRUE(std::filesystem::exists(store.batchFile(job, 0)));   // its rows are still queued

  std::vector<QueuedBatch> batches;
  const LeaseRecord first = store.openLease({job, 1, 0, 20}, "w", 1000, 2, batches);
  ASSERT_EQ(batches.size(), 2u);
  EXPECT_EQ(batches[1].payload, std::string(600, '2'));
  store.reclaimBatchFiles();
  EXPECT_TRUE(std::filesystem::exists(store.batchFile(job, 0)));   // leased is not consumed
  store.completeLease(first.id);
  store.reclaimBatchFiles();
  EXPECT_FALSE(std::filesystem::exists(store.batchFile(job, 0)));
  EXPECT_TRUE(std::filesystem::exists(store.batchFile(job, 1)));   // still written to

  const LeaseRecord second = store.openLease({job, 2, 0, 10}, "w", 1000, 3, batches);
  EXPECT_EQ(batches.at(0).payload, std::string(600, '3'));
  store.completeLease(second.id);
  {
    // An end that rolls back: the job goes on, and what it queues next is kept.
    sql::Transaction tx(store.database());
    store.setJobState(job, JobState::Done, 4);
  }
  store.reclaimBatchFiles();
  store.addBatch(job, 2, 0, BatchKind::Rays, 10, "after");
  store.reclaimBatchFiles();
  const LeaseRecord third = store.openLease({job, 2, 0, 10}, "w", 1000, 5, batches);
  EXPECT_EQ(batches.at(0).payload, "after");
  store.completeLease(third.id);
  // The committed end deletes every file of the job.
  store.setJobState(job, JobState::Done, 6);
  store.reclaimBatchFiles();
  EXPECT_TRUE(std::filesystem::is_empty(store.batchFile(job, 0).parent_path()));
}

TEST_F(JobStoreTest, BatchFilesNoRowRefersToAreDeletedAtStart) {
  std::filesystem::path kept, orphan, consumed;
  {
    JobStore store(path_.string());
    const uint64_t job = store.createJob("spec", 1);
    store.addBatch(job, 1, 0, BatchKind::Rays, 10, "kept");
    kept = store.batchFile(job, 0);
    consumed = store.batchFile(job, 3);   // a segment of a known job that no row refers to
    orphan = store.batchFile(job + 1, 0);   // a submit killed before its transaction committed
  }
  for (const auto& path : {orphan, consumed}) {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::fputs("no row refers to this", f);
    std::fclose(f);
  }
  const std::filesystem::path stranger = orphan.parent_path() / "notes.txt";
  std::fclose(std::fopen(stranger.c_str(), "wb"));
  JobStore reopened(path_.string());
  EXPECT_TRUE(std::filesystem::exists(kept));
  EXPECT_FALSE(std::filesystem::exists(orphan));
  EXPECT_FALSE(std::filesystem::exists(consumed));
  EXPECT_TRUE(std::filesystem::exists(stranger));   // not a name the store writes
}

// Files of jobs jobs.db does not have, beyond what a killed submit leaves
// (photons, later segments, ids past a gap), mean jobs.db lost commits: the
// store refuses to open, naming the jobs, and deletes nothing.
TEST_F(JobStoreTest, FilesOfJobsTheDatabaseLacksRefuseTheStartAndStay) {
  std::filesystem::path photons;
  {
    JobStore store(path_.string());
    const uint64_t job = store.createJob("spec", 1);
    photons = store.photonFile(job + 1);
  }
  std::filesystem::create_directories(photons.parent_path());
  std::FILE* f = std::fopen(photons.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  std::fputs("photons of a job whose rows are gone", f);
  std::fclose(f);
  try {
    JobStore reopened(path_.string());
    ADD_FAILURE() << "opened";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("hold files of 1 jobs it does not have (job 2)"), std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(std::filesystem::exists(photons));
}

TEST_F(JobStoreTest, ADamagedRayBatchIsReportedNamingTheFileAndNothingIsLeased) {
  std::filesystem::path file;
  {
    JobStore store(path_.string());
    const uint64_t job = store.createJob("spec", 1);
    file = store.batchFile(job, 0);
    store.addBatch(job, 4, 0, BatchKind::Rays, 10, std::string(200, 'x'));
  }
  overwriteByte(file, 50);
  JobStore reopened(path_.string());
  std::vector<QueuedBatch> batches;
  try {
    sql::Transaction tx(reopened.database());
    reopened.openLease(reopened.pendingCells(1).at(0), "w", 100, 2, batches);
    FAIL() << "a damaged batch was leased";
  } catch (const DamagedFileError& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("damaged"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(reopened.openLeases().empty());
  ASSERT_EQ(reopened.pendingCells(1).size(), 1u);
  EXPECT_EQ(reopened.pendingCells(1)[0].cell, 4u);
}

TEST_F(JobStoreTest, MigratingToVersionFourRechecksumsPhotonFilesAndKeepsDamageVisible) {
  const std::string good(240, 'g'), bad(240, 'b');
  int64_t secondOffset = 0;
  {
    JobStore store(path_.string());
    const uint64_t job = store.createJob("spec", 1);
    store.addPhotons(job, 1, 10, good);
    store.addPhotons(job, 2, 10, bad);
    secondOffset = lastPhotonBatchOffset(store);
    // Back to version 3: zlib's CRC-32 in the rows, no file columns in batches.
    for (const char* column : {"file_segment", "file_offset", "file_size", "file_crc"})
      store.database().exec(std::string("ALTER TABLE batches DROP COLUMN ") + column);
    store.database().exec(
        "INSERT INTO batches(job, cell, phase, kind, work, payload) VALUES (1, 6, 0, 0, 40, 'version three')");
    auto& update = store.database().prepare("UPDATE photons SET file_crc = ? WHERE cell = ?");
    for (const auto& [cell, bytes] : {std::pair{1, good}, std::pair{2, bad}}) {
      const uint32_t zlibCrc = uint32_t(crc32(0, reinterpret_cast<const Bytef*>(bytes.data()), uInt(bytes.size())));
      update.bind(1, int64_t(zlibCrc)).bind(2, int64_t(cell));
      update.run();
    }
    store.database().exec("ALTER TABLE jobs DROP COLUMN photon_record_bytes");
    store.database().exec("DROP TABLE render_progress; DROP TABLE render_passes");   // schema 7
    store.database().exec("DROP TABLE lease_log");   // schema 8
    dropVersionSixColumns(store);
    store.database().exec("ALTER TABLE jobs DROP COLUMN photon_region_end");   // schema 11
    store.database().exec("DROP TABLE job_sensors");   // schema 12
    dropVersionThirteenColumns(store);
    store.database().setUserVersion(3);
  }
  overwriteByte(path_.string() + "-photons/job-1.bin", secondOffset + 7);   // the second batch
  JobStore migrated(path_.string());
  EXPECT_EQ(migrated.database().userVersion(), JobStore::kSchemaVersion);
  EXPECT_EQ(migrated.job(1)->photonRecordBytes, 24);   // written before schema 5
  EXPECT_EQ(migrated.photonBatches(1, 1), std::vector<std::string>{good});
  EXPECT_THROW(migrated.photonBatches(1, 2), DamagedFileError);
  std::vector<QueuedBatch> batches;
  migrated.openLease(migrated.pendingCells(1).at(0), "w", 100, 2, batches);
  ASSERT_EQ(batches.size(), 1u);
  EXPECT_EQ(batches[0].payload, "version three");
}

}  // namespace
}  // namespace portico
