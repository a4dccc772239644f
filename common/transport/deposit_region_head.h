// The first block of a deposit region (proto/wire.capnp, DepositRegion):
// what the coordinator writes there when it sets the region aside, and what
// a worker checks before writing its lease's deposits after it.
//
// The block names the job and the lease, so a worker that opened some other
// file of the same name (another machine's, a job file of another
// coordinator) finds it is not its region and sends its deposits in the
// Result instead; and it holds a random nonce the worker returns
// (Result.regionNonce), so the coordinator accepts the region's deposits
// only from a worker that did read its file.
#pragma once

#include <array>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <string_view>

namespace portico::deposit_region {

// The head block: the deposits start after it, and every region is whole
// blocks, so that direct I/O (O_DIRECT) may write and read them.
constexpr int64_t kBlockBytes = 4096;
using Nonce = std::array<uint8_t, 16>;

// magic (16 bytes, "portico-region" and two zeros), job, lease (little-endian), nonce.
constexpr char kMagic[16] = {'p', 'o', 'r', 't', 'i', 'c', 'o', '-', 'r', 'e', 'g', 'i', 'o', 'n', 0, 0};
constexpr size_t kHeadBytes = sizeof(kMagic) + 8 + 8 + sizeof(Nonce);

inline std::string encodeHead(uint64_t job, uint64_t lease, const Nonce& nonce) {
  std::string head(kHeadBytes, '\0');
  std::memcpy(head.data(), kMagic, sizeof(kMagic));
  for (int byte = 0; byte < 8; ++byte) {
    head[sizeof(kMagic) + byte] = char(job >> (8 * byte));
    head[sizeof(kMagic) + 8 + byte] = char(lease >> (8 * byte));
  }
  std::memcpy(head.data() + sizeof(kMagic) + 16, nonce.data(), nonce.size());
  return head;
}

// The nonce of a head block that names this job and lease; nothing for any
// other bytes.
inline std::optional<Nonce> nonceOf(std::string_view block, uint64_t job, uint64_t lease) {
  if (block.size() < kHeadBytes || std::memcmp(block.data(), kMagic, sizeof(kMagic)) != 0) return std::nullopt;
  uint64_t readJob = 0, readLease = 0;
  for (int byte = 0; byte < 8; ++byte) {
    readJob |= uint64_t(uint8_t(block[sizeof(kMagic) + byte])) << (8 * byte);
    readLease |= uint64_t(uint8_t(block[sizeof(kMagic) + 8 + byte])) << (8 * byte);
  }
  if (readJob != job || readLease != lease) return std::nullopt;
  Nonce nonce;
  std::memcpy(nonce.data(), block.data() + sizeof(kMagic) + 16, nonce.size());
  return nonce;
}

}  // namespace portico::deposit_region
