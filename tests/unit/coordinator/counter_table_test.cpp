#include "coordinator/counter_table.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <stdexcept>

namespace portico {
namespace {

// A real SQLite file with jobs.db's counters table; the table observes its
// transactions as JobStore's does.
class CounterTableTest : public ::testing::Test {
 protected:
  void SetUp() override {
    path_ = std::filesystem::temp_directory_path() /
            ("portico-counters-" + std::to_string(getpid()) + "-" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name() + ".db");
    remove();
    db_ = std::make_unique<sql::Database>(path_.string(), sql::Database::Mode::ReadWriteCreate);
    db_->exec("CREATE TABLE counters (job INTEGER NOT NULL, name TEXT NOT NULL, value INTEGER NOT NULL, "
              "PRIMARY KEY (job, name))");
    table_ = std::make_unique<CounterTable>(*db_);
    db_->setObserver(table_.get());
  }
  void TearDown() override {
    db_->setObserver(nullptr);
    table_.reset();
    db_.reset();
    remove();
  }
  void remove() {
    for (const char* suffix : {"", "-wal", "-shm", "-journal"}) std::filesystem::remove(path_.string() + suffix);
  }
  // What the file holds, read by a statement (not through the table).
  int64_t stored(uint64_t job, const std::string& name) {
    auto& s = db_->prepare("SELECT value FROM counters WHERE job = ? AND name = ?");
    s.bind(1, int64_t(job)).bind(2, name);
    const int64_t value = s.step() ? s.columnInt(0) : -1;
    s.reset();
    return value;
  }
  int64_t value(uint64_t job, const std::string& name) {
    const auto& values = table_->of(job);
    const auto it = values.find(name);
    return it == values.end() ? -1 : it->second;
  }
  std::filesystem::path path_;
  std::unique_ptr<sql::Database> db_;
  std::unique_ptr<CounterTable> table_;
};

TEST_F(CounterTableTest, OutsideATransactionAChangeIsWrittenAtOnce) {
  table_->add(1, "rays", 5);
  table_->add(1, "rays", 7);
  table_->raise(1, "peak", 30);
  table_->raise(1, "peak", 20);
  EXPECT_EQ(stored(1, "rays"), 12);
  EXPECT_EQ(stored(1, "peak"), 30);
  EXPECT_EQ(value(1, "peak"), 30);
}

TEST_F(CounterTableTest, InsideATransactionChangesAreWrittenOnlyWhenItCommits) {
  table_->add(1, "rays", 5);
  {
    sql::Transaction tx(*db_);
    table_->add(1, "rays", 10);
    table_->add(2, "photons", 3);
    EXPECT_EQ(value(1, "rays"), 15);   // read back before the commit
    EXPECT_EQ(stored(1, "rays"), 5);   // not written yet
    EXPECT_EQ(stored(2, "photons"), -1);
    tx.commit();
  }
  EXPECT_EQ(stored(1, "rays"), 15);
  EXPECT_EQ(stored(2, "photons"), 3);
  // A second table on the same file reads what was written.
  CounterTable fresh(*db_);
  EXPECT_EQ(fresh.of(1).at("rays"), 15);
}

TEST_F(CounterTableTest, ARolledBackTransactionLeavesMemoryAsTheFile) {
  table_->add(1, "rays", 5);
  {
    sql::Transaction tx(*db_);
    table_->add(1, "rays", 10);
    table_->add(1, "new", 1);
    table_->raise(1, "peak", 9);
  }   // not committed
  EXPECT_EQ(value(1, "rays"), 5);
  EXPECT_EQ(value(1, "new"), -1);
  EXPECT_EQ(value(1, "peak"), -1);
  // Nothing of it is written by the next transaction either.
  {
    sql::Transaction tx(*db_);
    table_->add(1, "other", 1);
    tx.commit();
  }
  EXPECT_EQ(stored(1, "rays"), 5);
  EXPECT_EQ(stored(1, "new"), -1);
}

TEST_F(CounterTableTest, ASavepointRolledBackUndoesOnlyItsOwnChanges) {
  {
    sql::Transaction round(*db_);
    table_->add(1, "rays", 5);
    {
      sql::Transaction kept(*db_);
      table_->add(1, "rays", 1);
      kept.commit();
    }
    {
      sql::Transaction refused(*db_);
      table_->add(1, "rays", 100);
      table_->add(1, "refused", 1);
      {
        sql::Transaction inner(*db_);
        table_->add(1, "rays", 1000);
        inner.commit();
      }
    }   // rolled back, with the savepoint released into it
    table_->add(1, "rays", 2);
    EXPECT_EQ(value(1, "rays"), 8);
    round.commit();
  }
  EXPECT_EQ(stored(1, "rays"), 8);
  EXPECT_EQ(stored(1, "refused"), -1);
}

TEST_F(CounterTableTest, AFailedCommitRestoresWhatTheFileHolds) {
  table_->add(1, "rays", 5);
  // A trigger refuses the write-back, so the commit fails after the
  // table's values changed.
  db_->exec("CREATE TRIGGER refuse BEFORE UPDATE ON counters WHEN NEW.value > 100 "
            "BEGIN SELECT RAISE(ABORT, 'refused'); END");
  try {
    sql::Transaction tx(*db_);
    table_->add(1, "rays", 1000);
    tx.commit();
    FAIL() << "the commit should have failed";
  } catch (const std::exception&) {
  }
  EXPECT_EQ(value(1, "rays"), 5);
  EXPECT_EQ(stored(1, "rays"), 5);
}

TEST_F(CounterTableTest, DroppingAJobsCountersKeepsOneAndRollsBack) {
  table_->add(1, "rays", 5);
  table_->add(1, "restarts", 1);
  table_->add(2, "rays", 7);
  {
    sql::Transaction tx(*db_);
    table_->dropAllBut(1, "restarts");
    EXPECT_EQ(value(1, "rays"), -1);
  }   // rolled back
  EXPECT_EQ(value(1, "rays"), 5);
  EXPECT_EQ(stored(1, "rays"), 5);
  {
    sql::Transaction tx(*db_);
    table_->add(1, "rays", 1);   // changed, then dropped: not written back
    table_->dropAllBut(1, "restarts");
    tx.commit();
  }
  EXPECT_EQ(stored(1, "rays"), -1);
  EXPECT_EQ(stored(1, "restarts"), 1);
  EXPECT_EQ(stored(2, "rays"), 7);
  table_->forget(1);
  EXPECT_EQ(value(1, "restarts"), 1);   // read again from the file
}

}  // namespace
}  // namespace portico
