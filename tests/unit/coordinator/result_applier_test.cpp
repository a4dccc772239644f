#include "coordinator/result_applier.h"

#include <capnp/message.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <initializer_list>
#include <utility>

#include "common/transport/film.h"
#include "common/transport/photon_record.h"
#include "coordinator/job_report.h"
#include "coordinator/result_check.h"

namespace portico {
namespace {

// A real jobs.db and its files, in a directory of the test's own.
// Fills a Result's crossings: per entry, a cell and how many rays go to it.
void queueCrossings(wire::Result::Builder result, std::initializer_list<std::pair<uint32_t, uint32_t>> cellsAndRays) {
  auto crossings = result.initCrossings(static_cast<unsigned>(cellsAndRays.size()));
  unsigned i = 0;
  for (const auto& [cell, rays] : cellsAndRays) {
    crossings[i].setCell(cell);
    crossings[i++].initRays(rays);
  }
}

class ResultApplierTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("portico-result-applier-" + std::to_string(getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    store_ = std::make_unique<JobStore>((dir_ / "jobs.db").string());
    job_ = store_->createJob("spec", 1);
  }
  void TearDown() override {
    store_.reset();
    std::filesystem::remove_all(dir_);
  }
  ResultTarget target(int phase) const { return {77, job_, phase, 4, 16}; }
  std::filesystem::path dir_;
  std::unique_ptr<JobStore> store_;
  uint64_t job_ = 0;
};

TEST_F(ResultApplierTest, CrossingsDepositsAndFilmGoWhereTheResultSays) {
  capnp::MallocMessageBuilder message;
  auto result = message.initRoot<wire::Result>();
  queueCrossings(result, {{2, 3}, {3, 5}});
  auto deposits = result.initDeposits(1);
  deposits[0].setCell(1);
  std::string records(2 * sizeof(PhotonRecord), 'x');
  deposits[0].setRecords(capnp::Data::Reader(reinterpret_cast<const kj::byte*>(records.data()), records.size()));
  {
    sql::Transaction tx(store_->database());
    applyResult(*store_, target(0), nullptr, result.asReader());
    tx.commit();
  }
  EXPECT_EQ(store_->queuedRays(job_, 0), 8);
  const auto pending = store_->pendingCells(10);
  ASSERT_EQ(pending.size(), 2u);
  EXPECT_EQ(pending[0].cell, 3u);   // most work first
  EXPECT_EQ(pending[0].work, 5);
  EXPECT_EQ(pending[1].cell, 2u);
  const auto photons = store_->photonBatches(job_, 1);
  ASSERT_EQ(photons.size(), 1u);
  EXPECT_EQ(photons[0], records);
  EXPECT_EQ(store_->counters(job_).at(std::string(kPhotonBytesFromResultsCounter)), int64_t(records.size()));

  capnp::MallocMessageBuilder render;
  auto film = render.initRoot<wire::Result>().initFilm(2);
  film[0].setPixel(5);
  film[0].setR(10);
  film[1].setPixel(5);
  film[1].setR(20);
  film[1].setB(1);
  {
    sql::Transaction tx(store_->database());
    applyResult(*store_, target(1), nullptr, render.getRoot<wire::Result>().asReader());
    tx.commit();
  }
  const auto pixels = store_->film(job_, 16);
  EXPECT_EQ(pixels[5].r, 30);
  EXPECT_EQ(pixels[5].b, 1);
  EXPECT_EQ(pixels[4].r, 0);
}

TEST_F(ResultApplierTest, ACellThatDoesNotExistIsRefusedAndNothingIsKept) {
  capnp::MallocMessageBuilder message;
  auto result = message.initRoot<wire::Result>();
  queueCrossings(result, {{1, 3}, {4, 1}});   // the store has cells 0-3
  {
    sql::Transaction tx(store_->database());
    EXPECT_THROW(applyResult(*store_, target(0), nullptr, result.asReader()), BadResultError);
  }
  EXPECT_EQ(store_->queuedRays(job_, 0), 0);
  EXPECT_TRUE(store_->pendingCells(10).empty());
}

TEST_F(ResultApplierTest, PartialRecordsAndFilmBeyondItsRangeAreRefusedWithTheirCountersUndone) {
  capnp::MallocMessageBuilder message;
  auto result = message.initRoot<wire::Result>();
  auto deposits = result.initDeposits(1);
  deposits[0].setCell(0);
  std::string records(sizeof(PhotonRecord) + 3, 'x');
  deposits[0].setRecords(capnp::Data::Reader(reinterpret_cast<const kj::byte*>(records.data()), records.size()));
  {
    sql::Transaction tx(store_->database());
    EXPECT_THROW(applyResult(*store_, target(0), nullptr, result.asReader()), BadResultError);
  }
  // Whole records, then a film sum that overflows: the deposits' counter,
  // added before the film was read, is undone with the rest.
  capnp::MallocMessageBuilder overflowing;
  auto bad = overflowing.initRoot<wire::Result>();
  auto whole = bad.initDeposits(1);
  whole[0].setCell(0);
  std::string one(sizeof(PhotonRecord), 'y');
  whole[0].setRecords(capnp::Data::Reader(reinterpret_cast<const kj::byte*>(one.data()), one.size()));
  auto film = bad.initFilm(2);
  film[0].setPixel(1);
  film[0].setR(kFilmMaxSum);
  film[1].setPixel(1);
  film[1].setR(kFilmMaxSum);
  {
    sql::Transaction round(store_->database());
    {
      sql::Transaction tx(store_->database());
      EXPECT_THROW(applyResult(*store_, target(1), nullptr, bad.asReader()), FilmRangeError);
    }
    round.commit();
  }
  EXPECT_TRUE(store_->photonBatches(job_, 0).empty());
  EXPECT_EQ(store_->counters(job_).count(std::string(kPhotonBytesFromResultsCounter)), 0u);
}

}  // namespace
}  // namespace portico
