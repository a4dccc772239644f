// Deposit regions (coordinator/deposit_regions.h): what a Result may name
// in its lease's region, the region's head, and how the job store sets
// regions aside so that none is ever handed out twice.
#include "coordinator/deposit_regions.h"

#include <capnp/message.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "common/transport/deposit_region_head.h"
#include "common/util/crc32c.h"
#include "coordinator/job_store.h"

namespace portico {
namespace {

DepositRegionGrant grantAt(int64_t offset, int64_t size) {
  DepositRegionGrant grant;
  grant.offset = offset;
  grant.size = size;
  for (size_t i = 0; i < grant.nonce.size(); ++i) grant.nonce[i] = uint8_t(7 * i + 1);
  return grant;
}

struct FileDeposit {
  uint32_t cell;
  uint64_t offset, size;
};

// A Result with these deposits in its region (and one cell's records inline), with `nonce`.
std::unique_ptr<capnp::MallocMessageBuilder> resultWith(const std::vector<FileDeposit>& inRegion,
                                                        const deposit_region::Nonce* nonce, bool inlineToo = true) {
  auto message = std::make_unique<capnp::MallocMessageBuilder>();
  auto result = message->initRoot<wire::Result>();
  result.setLease(9);
  auto deposits = result.initDeposits(unsigned(inRegion.size() + (inlineToo ? 1 : 0)));
  for (size_t i = 0; i < inRegion.size(); ++i) {
    deposits[unsigned(i)].setCell(inRegion[i].cell);
    deposits[unsigned(i)].setFileOffset(inRegion[i].offset);
    deposits[unsigned(i)].setFileSize(inRegion[i].size);
    deposits[unsigned(i)].setFileCrc(123);
  }
  if (inlineToo) {
    const std::string records(32, 'r');
    deposits[unsigned(inRegion.size())].setCell(5);
    deposits[unsigned(inRegion.size())].setRecords(
        capnp::Data::Reader(reinterpret_cast<const kj::byte*>(records.data()), records.size()));
  }
  if (nonce) result.setRegionNonce(capnp::Data::Reader(nonce->data(), nonce->size()));
  return message;
}

std::string errorOf(const DepositRegionGrant* grant, capnp::MallocMessageBuilder& message, size_t cells = 10) {
  try {
    regionDeposits(9, grant, message.getRoot<wire::Result>().asReader(), cells);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(DepositRegions, AcceptsWholeRecordsInsideTheRegionAfterItsHead) {
  const DepositRegionGrant grant = grantAt(8192, 4096 + 8192);
  auto message = resultWith({{1, 8192 + 4096, 160}, {2, 8192 + 4096 + 160, 8192 - 160}}, &grant.nonce);
  const auto deposits = regionDeposits(9, &grant, message->getRoot<wire::Result>().asReader(), 10);
  ASSERT_EQ(deposits.size(), 2u);
  EXPECT_EQ(deposits[0].cell, 1u);
  EXPECT_EQ(deposits[0].extent.offset, 8192 + 4096);
  EXPECT_EQ(deposits[0].extent.size, 160);
  EXPECT_EQ(deposits[0].extent.crc, 123u);
  EXPECT_EQ(deposits[1].extent.offset + deposits[1].extent.size, grant.offset + grant.size);
  // Inline deposits alone, no nonce: nothing in a region, whether or not the lease had one.
  auto inlineOnly = resultWith({}, nullptr);
  EXPECT_TRUE(regionDeposits(9, nullptr, inlineOnly->getRoot<wire::Result>().asReader(), 10).empty());
  EXPECT_TRUE(regionDeposits(9, &grant, inlineOnly->getRoot<wire::Result>().asReader(), 10).empty());
}

TEST(DepositRegions, RefusesWhatTheLeaseWasNotGivenNamingTheProblem) {
  const DepositRegionGrant grant = grantAt(8192, 4096 + 8192);
  const int64_t first = 8192 + 4096, end = 8192 + 4096 + 8192;
  deposit_region::Nonce other = grant.nonce;
  other[3] ^= 1;
  const auto expect = [&](const DepositRegionGrant* g, std::vector<FileDeposit> deposits,
                          const deposit_region::Nonce* nonce, const std::string& expected) {
    auto message = resultWith(deposits, nonce);
    const std::string error = errorOf(g, *message);
    EXPECT_NE(error.find(expected), std::string::npos) << error;
    EXPECT_NE(error.find("lease 9"), std::string::npos) << error;
  };
  expect(nullptr, {{1, uint64_t(first), 16}}, &grant.nonce, "names a deposit region it was not given");
  expect(&grant, {{1, uint64_t(first), 16}}, nullptr, "does not return its deposit region's nonce");
  expect(&grant, {{1, uint64_t(first), 16}}, &other, "does not return its deposit region's nonce");
  expect(&grant, {{1, uint64_t(first), 20}}, &grant.nonce, "not whole records");
  expect(&grant, {{1, uint64_t(grant.offset), 16}}, &grant.nonce, "outside its deposit region");   // the head
  expect(&grant, {{1, uint64_t(end - 16), 32}}, &grant.nonce, "outside its deposit region");
  expect(&grant, {{1, uint64_t(end), 16}}, &grant.nonce, "outside its deposit region");
  expect(&grant, {{1, ~uint64_t(0) - 8, 16}}, &grant.nonce, "outside its deposit region");
  expect(&grant, {{1, uint64_t(first), uint64_t(1) << 62}}, &grant.nonce, "outside its deposit region");
  expect(&grant, {{1, uint64_t(first), ~uint64_t(0) - 15}}, &grant.nonce, "not whole records");
  expect(&grant, {{1, uint64_t(first), 64}, {2, uint64_t(first + 48), 32}}, &grant.nonce, "overlapping photons");
  expect(&grant, {{10, uint64_t(first), 16}}, &grant.nonce, "cell 10, which does not exist");
  // Both ways at once for one cell.
  auto both = resultWith({{5, uint64_t(first), 16}}, &grant.nonce);
  both->getRoot<wire::Result>().getDeposits()[0].setRecords(
      capnp::Data::Reader(reinterpret_cast<const kj::byte*>("0123456789abcdef"), 16));
  EXPECT_NE(errorOf(&grant, *both).find("both in the result and in its deposit region"), std::string::npos);
}

TEST(DepositRegions, SizesRegionsInWholeBlocksForTheLeaseWork) {
  const int64_t block = deposit_region::kBlockBytes;
  for (int64_t work : {int64_t(0), int64_t(1), int64_t(31), int64_t(32), int64_t(33), int64_t(40000)})
    for (size_t cells : {size_t(1), size_t(16)}) {
      const int64_t bytes = depositRegionBytes(work, cells);
      EXPECT_EQ(bytes % block, 0) << work;
      EXPECT_GE(bytes, block + std::max<int64_t>(work, 1) * kRegionBytesPerWork) << work;
      EXPECT_GE(bytes, block * int64_t(1 + cells)) << work;
    }
  EXPECT_EQ(depositRegionBytes(int64_t(1) << 40, 1), kMostRegionBytes);
}

TEST(DepositRegionHead, NamesItsJobAndLeaseAndCarriesTheNonce) {
  deposit_region::Nonce nonce;
  for (size_t i = 0; i < nonce.size(); ++i) nonce[i] = uint8_t(200 + i);
  std::string block = deposit_region::encodeHead(0x0102030405060708ull, 77, nonce);
  block.resize(deposit_region::kBlockBytes, '\0');
  EXPECT_EQ(deposit_region::nonceOf(block, 0x0102030405060708ull, 77), nonce);
  EXPECT_FALSE(deposit_region::nonceOf(block, 0x0102030405060708ull, 78));
  EXPECT_FALSE(deposit_region::nonceOf(block, 1, 77));
  EXPECT_FALSE(deposit_region::nonceOf(std::string(deposit_region::kBlockBytes, '\0'), 0, 0));
  EXPECT_FALSE(deposit_region::nonceOf(block.substr(0, 20), 0x0102030405060708ull, 77));
  block[3] = 'X';
  EXPECT_FALSE(deposit_region::nonceOf(block, 0x0102030405060708ull, 77));
}

class DepositRegionStore : public ::testing::Test {
 protected:
  void SetUp() override {
    path_ = std::filesystem::temp_directory_path() /
            ("portico-regions-" + std::to_string(getpid()) + "-" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name() + ".db");
    TearDown();
  }
  void TearDown() override {
    for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(path_.string() + suffix);
    std::filesystem::remove_all(path_.string() + "-photons");
    std::filesystem::remove_all(path_.string() + "-batches");
  }
  std::string readAt(const std::filesystem::path& file, int64_t offset, size_t size) {
    std::ifstream in(file, std::ios::binary);
    in.seekg(offset);
    std::string bytes(size, '\0');
    in.read(bytes.data(), std::streamsize(size));
    return bytes.substr(0, size_t(in.gcount()));
  }
  std::filesystem::path path_;
};

// A region is set aside past everything written, its head written at its
// start; photons recorded in it read back (CRC-checked); and no later
// batch or region starts inside it, even after the coordinator restarts
// with the region's lease never completed, or the photon pass restarts.
TEST_F(DepositRegionStore, RegionsAreNeverHandedOutTwiceAcrossRestarts) {
  const int64_t block = deposit_region::kBlockBytes;
  std::filesystem::path file;
  int64_t first = 0, second = 0;
  const std::string records(48, 'd');
  {
    JobStore store(path_.string());
    const uint64_t job = store.createJob("spec", 1);
    file = store.photonFile(job);
    store.addPhotons(job, 0, 2, std::string(32, 'a'));
    {
      sql::Transaction tx(store.database());
      first = store.reserveDepositRegion(job, 4 * block, "head-one");
      tx.commit();
    }
    EXPECT_EQ(first % block, 0);
    EXPECT_GE(first, 32);
    EXPECT_EQ(readAt(file, first, 8), "head-one");
    // A worker writes after the head; the Result records where.
    std::fstream out(file, std::ios::in | std::ios::out | std::ios::binary);
    out.seekp(first + block);
    out.write(records.data(), std::streamsize(records.size()));
    out.close();
    {
      sql::Transaction tx(store.database());
      store.addPhotonsAt(job, 3, FileExtent{first + block, int64_t(records.size()), crc32c(records.data(), records.size())});
      second = store.reserveDepositRegion(job, 2 * block, "head-two");   // its lease never completes
      tx.commit();
    }
    EXPECT_GE(second, first + 4 * block);
    EXPECT_EQ(store.photonBatches(job, 3), std::vector<std::string>{records});
    // A wrong CRC is damage, found on reading.
    {
      sql::Transaction tx(store.database());
      store.addPhotonsAt(job, 4, FileExtent{first + block, 16, 0});
      tx.commit();
    }
    EXPECT_THROW(store.photonBatches(job, 4), DamagedFileError);
  }
  {
    // Restarted: the file resumes past the second region, though nothing
    // committed names it (a worker may still be writing into it).
    JobStore store(path_.string());
    store.addPhotons(1, 0, 1, std::string(16, 'z'));
    auto& s = store.database().prepare("SELECT MAX(file_offset) FROM photons WHERE cell = 0");
    ASSERT_TRUE(s.step());
    EXPECT_GE(s.columnInt(0), second + 2 * block);
    s.reset();
    EXPECT_EQ(readAt(file, second, 8), "head-two");
    EXPECT_EQ(store.photonBatches(1, 3), std::vector<std::string>{records});
    // A restarted photon pass drops the rows, not the regions' reach.
    store.restartJob(1, 5);
    sql::Transaction tx(store.database());
    EXPECT_GE(store.reserveDepositRegion(1, block * 2, "head-three"), second + 2 * block);
    tx.commit();
  }
  // A region whose transaction rolled back is not kept in jobs.db, but the
  // open file still moves past it.
  JobStore store(path_.string());
  int64_t rolledBack = 0;
  {
    sql::Transaction tx(store.database());
    rolledBack = store.reserveDepositRegion(1, block * 2, "head-four");
  }
  sql::Transaction tx(store.database());
  EXPECT_GE(store.reserveDepositRegion(1, block * 2, "head-five"), rolledBack + 2 * block);
  tx.commit();
  // Disk use is what was written: the regions' unwritten blocks are holes.
  EXPECT_LT(store.jobFileBytes(1).photons, int64_t(std::filesystem::file_size(file)));
}

TEST_F(DepositRegionStore, ABadRegionRequestIsRefused) {
  JobStore store(path_.string());
  const uint64_t job = store.createJob("spec", 1);
  EXPECT_THROW(store.reserveDepositRegion(job, 100, "h"), std::invalid_argument);
  EXPECT_THROW(store.reserveDepositRegion(job, 0, "h"), std::invalid_argument);
  EXPECT_THROW(store.reserveDepositRegion(job, 4096, std::string(4097, 'h')), std::invalid_argument);
}

}  // namespace
}  // namespace portico
