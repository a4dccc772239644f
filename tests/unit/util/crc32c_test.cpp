#include "common/util/crc32c.h"

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

namespace portico {
namespace {

// Bit by bit, straight from the definition (reflected, polynomial 0x82F63B78).
uint32_t crcByDefinition(const std::string& bytes) {
  uint32_t crc = ~0u;
  for (unsigned char byte : bytes) {
    crc ^= byte;
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ ((crc & 1) ? 0x82F63B78u : 0u);
  }
  return ~crc;
}

TEST(Crc32c, MatchesTheStandardCheckValues) {
  EXPECT_EQ(crc32c("123456789", 9), 0xE3069283u);   // the catalogue's check value
  EXPECT_EQ(crc32c("", 0), 0u);
  const std::string zeros(32, '\0'), ones(32, '\xff');
  EXPECT_EQ(crc32c(zeros.data(), zeros.size()), 0x8A9136AAu);   // RFC 3720, B.4
  EXPECT_EQ(crc32c(ones.data(), ones.size()), 0x62A8AB43u);
}

TEST(Crc32c, AgreesWithTheDefinitionAtEveryLengthAndAlignment) {
  std::mt19937 random(7);
  std::string bytes(300, '\0');
  for (char& c : bytes) c = char(random());
  for (size_t start = 0; start < 9; ++start)
    for (size_t length = 0; length + start <= bytes.size(); length += 1 + length / 8) {
      const std::string piece = bytes.substr(start, length);
      EXPECT_EQ(crc32c(bytes.data() + start, length), crcByDefinition(piece)) << start << " " << length;
    }
}

// Lengths around the hardware path's blocks of three streams (3 x 4096 and
// 3 x 256 bytes), where the streams' CRCs are combined.
TEST(Crc32c, AgreesWithTheDefinitionOnLongInputsAcrossStreamBlocks) {
  std::mt19937 random(11);
  std::string bytes(3 * 4096 * 2 + 3 * 256 * 3 + 64, '\0');
  for (char& c : bytes) c = char(random());
  for (size_t length : {size_t(767), size_t(768), size_t(769), size_t(3 * 4096 - 1), size_t(3 * 4096),
                        size_t(3 * 4096 + 8), size_t(3 * 4096 + 3 * 256 + 7), size_t(6 * 4096 + 1),
                        bytes.size() - 5})
    for (size_t start : {size_t(0), size_t(3)}) {
      const std::string piece = bytes.substr(start, length);
      EXPECT_EQ(crc32c(piece.data(), piece.size()), crcByDefinition(piece)) << start << " " << length;
      const size_t split = length / 3 + 1;
      EXPECT_EQ(crc32c(piece.data() + split, length - split, crc32c(piece.data(), split)), crcByDefinition(piece));
    }
}

TEST(Crc32c, ContinuesAcrossPieces) {
  const std::string text = "the photons a job deposits, and the rays queued between cells";
  for (size_t split = 0; split <= text.size(); ++split)
    EXPECT_EQ(crc32c(text.data() + split, text.size() - split, crc32c(text.data(), split)),
              crc32c(text.data(), text.size()));
}

}  // namespace
}  // namespace portico
