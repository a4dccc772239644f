// The worker's side of deposit regions (worker/deposit_region_writer.h):
// deposits land after the head, every cell's records where the extents
// say, with their CRCs; a region that is not this lease's, a file that does
// not open, or a region too small sends (some) deposits in the Result.
#include "worker/deposit_region_writer.h"

#include <capnp/message.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <csignal>

#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <memory>
#include <string>
#include <vector>

#include "common/transport/deposit_region_head.h"
#include "common/util/crc32c.h"

namespace portico {
namespace {

namespace fs = std::filesystem;
constexpr int64_t kBlock = deposit_region::kBlockBytes;

class DepositRegionWriterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("portico-region-writer-" + std::to_string(getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    file_ = dir_ / "job-1.bin";
    for (size_t i = 0; i < nonce_.size(); ++i) nonce_[i] = uint8_t(31 * i + 5);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // The coordinator's part: the head of lease `lease`'s region at `offset`.
  void writeHead(int64_t offset, uint64_t job, uint64_t lease) {
    std::fstream out(file_, std::ios::in | std::ios::out | std::ios::binary);
    if (!out) out.open(file_, std::ios::out | std::ios::binary);
    std::string block = deposit_region::encodeHead(job, lease, nonce_);
    block.resize(size_t(kBlock), '\0');
    out.seekp(offset);
    out.write(block.data(), std::streamsize(block.size()));
  }
  std::unique_ptr<capnp::MallocMessageBuilder> region(const fs::path& path, int64_t offset, int64_t size) {
    auto message = std::make_unique<capnp::MallocMessageBuilder>();
    auto target = message->initRoot<wire::DepositRegion>();
    target.setPath(path.string());
    target.setOffset(uint64_t(offset));
    target.setSize(uint64_t(size));
    return message;
  }
  std::string readAt(uint64_t offset, uint64_t size) {
    std::ifstream in(file_, std::ios::binary);
    in.seekg(std::streamoff(offset));
    std::string bytes(size, '\0');
    in.read(bytes.data(), std::streamsize(size));
    return bytes;
  }
  static std::vector<PhotonRecord> records(size_t count, uint64_t seed) {
    std::vector<PhotonRecord> out(count);
    for (size_t i = 0; i < count; ++i) out[i] = PhotonRecord{(seed * 1000 + i) | uint64_t(i) << 40};
    return out;
  }

  fs::path dir_, file_;
  deposit_region::Nonce nonce_{};
};

TEST_F(DepositRegionWriterTest, WritesEveryCellAfterTheHeadWhereItsExtentSays) {
  writeHead(2 * kBlock, 1, 42);
  const std::map<uint32_t, std::vector<PhotonRecord>> deposits{{3, records(300, 3)}, {7, records(5, 7)}};
  auto target = region(file_, 2 * kBlock, 4 * kBlock);
  DepositRegionWriter writer;
  const auto written = writer.write(target->getRoot<wire::DepositRegion>().asReader(), 1, 42, deposits);
  ASSERT_TRUE(written);
  std::string error;
  ASSERT_TRUE(writer.finish(42, error)) << error;
  EXPECT_EQ(written->nonce, nonce_);
  ASSERT_EQ(written->extents.size(), 2u);
  size_t index = 0;
  uint64_t next = uint64_t(3 * kBlock);
  for (const auto& [cell, cellRecords] : deposits) {
    ASSERT_TRUE(written->extents[index]) << cell;
    const auto& extent = *written->extents[index++];
    const std::string expected(reinterpret_cast<const char*>(cellRecords.data()), cellRecords.size() * sizeof(PhotonRecord));
    EXPECT_EQ(extent.offset, next);
    EXPECT_EQ(extent.size, expected.size());
    EXPECT_EQ(extent.crc, crc32c(expected.data(), expected.size()));
    EXPECT_EQ(readAt(extent.offset, extent.size), expected) << cell;
    next += extent.size;
  }
  // The head is left as the coordinator wrote it.
  EXPECT_EQ(deposit_region::nonceOf(readAt(2 * kBlock, kBlock), 1, 42), nonce_);
  // A lease without a pending write finishes at once.
  EXPECT_TRUE(writer.finish(43, error));
}

TEST_F(DepositRegionWriterTest, CellsThatDoNotFitGoInTheResult) {
  writeHead(0, 1, 5);
  // Room for 2 * 4096 bytes: a block of records, then more than a block
  // that do not fit, then a little less than a block that do.
  constexpr size_t perBlock = kBlock / sizeof(PhotonRecord);
  const std::map<uint32_t, std::vector<PhotonRecord>> deposits{
      {1, records(perBlock, 1)}, {2, records(perBlock * 300 / 256, 2)}, {3, records(perBlock * 250 / 256, 3)}};
  auto target = region(file_, 0, 3 * kBlock);
  DepositRegionWriter writer;
  const auto written = writer.write(target->getRoot<wire::DepositRegion>().asReader(), 1, 5, deposits);
  ASSERT_TRUE(written);
  std::string error;
  ASSERT_TRUE(writer.finish(5, error)) << error;
  ASSERT_EQ(written->extents.size(), 3u);
  EXPECT_TRUE(written->extents[0]);
  EXPECT_FALSE(written->extents[1]);
  EXPECT_TRUE(written->extents[2]);
  EXPECT_LE(written->extents[2]->offset + written->extents[2]->size, uint64_t(3 * kBlock));
}

TEST_F(DepositRegionWriterTest, ARegionThatIsNotThisLeasesOrAFileThatDoesNotOpenSendsEverythingInTheResult) {
  writeHead(0, 1, 5);
  const std::map<uint32_t, std::vector<PhotonRecord>> deposits{{1, records(10, 1)}};
  DepositRegionWriter writer;
  std::string error;
  for (const auto& [job, lease] : std::vector<std::pair<uint64_t, uint64_t>>{{1, 6}, {2, 5}}) {
    auto target = region(file_, 0, 2 * kBlock);
    EXPECT_FALSE(writer.write(target->getRoot<wire::DepositRegion>().asReader(), job, lease, deposits));
    EXPECT_TRUE(writer.finish(lease, error));
  }
  auto missing = region(dir_ / "elsewhere" / "job-1.bin", 0, 2 * kBlock);
  EXPECT_FALSE(writer.write(missing->getRoot<wire::DepositRegion>().asReader(), 1, 5, deposits));
  auto unaligned = region(file_, 100, 2 * kBlock);
  EXPECT_FALSE(writer.write(unaligned->getRoot<wire::DepositRegion>().asReader(), 1, 5, deposits));
  auto headOnly = region(file_, 0, kBlock);
  EXPECT_FALSE(writer.write(headOnly->getRoot<wire::DepositRegion>().asReader(), 1, 5, deposits));
  // Nothing was written past the head.
  EXPECT_EQ(fs::file_size(file_), uint64_t(kBlock));
}

// A write that fails (here: past the process's file size limit, as on a
// full disk) gives its records back, and they go in the Result instead.
TEST_F(DepositRegionWriterTest, AFailedWriteSendsItsRecordsInTheResult) {
  writeHead(0, 1, 5);
  const std::map<uint32_t, std::vector<PhotonRecord>> deposits{{2, records(200, 2)}, {4, records(300, 4)}};
  auto target = region(file_, 0, 4 * kBlock);
  DepositRegionWriter writer;
  std::optional<DepositRegionWriter::Written> written;
  std::string error;
  DepositRegionWriter::Unwritten unwritten;
  bool ok = true;
  {
    rlimit saved{};
    ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &saved), 0);
    const auto oldHandler = std::signal(SIGXFSZ, SIG_IGN);
    rlimit small = saved;
    small.rlim_cur = rlim_t(kBlock + 1000);
    ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
    written = writer.write(target->getRoot<wire::DepositRegion>().asReader(), 1, 5, deposits);
    if (written) ok = writer.finish(5, error, &unwritten);
    ::setrlimit(RLIMIT_FSIZE, &saved);
    std::signal(SIGXFSZ, oldHandler);
  }
  ASSERT_TRUE(written);
  EXPECT_FALSE(ok);
  EXPECT_NE(error.find(file_.string()), std::string::npos) << error;

  // The Result as encoded with the extents, then with the records back in it.
  capnp::MallocMessageBuilder message;
  auto result = message.initRoot<wire::Result>();
  result.setRegionNonce(capnp::Data::Reader(written->nonce.data(), written->nonce.size()));
  auto list = result.initDeposits(2);
  size_t index = 0;
  for (const auto& [cell, cellRecords] : deposits) {
    list[unsigned(index)].setCell(cell);
    list[unsigned(index)].setFileOffset(written->extents[index]->offset);
    list[unsigned(index)].setFileSize(written->extents[index]->size);
    list[unsigned(index)].setFileCrc(written->extents[index]->crc);
    ++index;
  }
  sendDepositsInResult(result, unwritten);
  EXPECT_EQ(result.getRegionNonce().size(), 0u);
  index = 0;
  for (const auto& [cell, cellRecords] : deposits) {
    auto d = result.getDeposits()[unsigned(index++)];
    EXPECT_EQ(d.getFileSize(), 0u);
    EXPECT_EQ(std::string(reinterpret_cast<const char*>(d.getRecords().begin()), d.getRecords().size()),
              std::string(reinterpret_cast<const char*>(cellRecords.data()), cellRecords.size() * sizeof(PhotonRecord)));
  }
  // The file is not used again by this writer: the next lease sends its records.
  writeHead(8 * kBlock, 1, 6);
  auto next = region(file_, 8 * kBlock, 2 * kBlock);
  EXPECT_FALSE(writer.write(next->getRoot<wire::DepositRegion>().asReader(), 1, 6, deposits));
}

// The file was replaced since the writer opened it (a job's file removed
// and made anew): the writer opens it again and finds the new head.
TEST_F(DepositRegionWriterTest, AFileReplacedSinceItWasOpenedIsOpenedAgain) {
  writeHead(0, 1, 5);
  const std::map<uint32_t, std::vector<PhotonRecord>> deposits{{1, records(10, 1)}};
  DepositRegionWriter writer;
  std::string error;
  auto target = region(file_, 0, 2 * kBlock);
  ASSERT_TRUE(writer.write(target->getRoot<wire::DepositRegion>().asReader(), 1, 5, deposits));
  ASSERT_TRUE(writer.finish(5, error));
  fs::remove(file_);
  writeHead(kBlock, 1, 6);
  auto again = region(file_, kBlock, 2 * kBlock);
  const auto written = writer.write(again->getRoot<wire::DepositRegion>().asReader(), 1, 6, deposits);
  ASSERT_TRUE(written);
  ASSERT_TRUE(writer.finish(6, error)) << error;
  EXPECT_EQ(readAt(written->extents[0]->offset, written->extents[0]->size),
            std::string(reinterpret_cast<const char*>(deposits.at(1).data()), 10 * sizeof(PhotonRecord)));
}

}  // namespace
}  // namespace portico
