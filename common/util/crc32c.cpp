#include "common/util/crc32c.h"

#include <array>
#include <cstring>

#if defined(__x86_64__)
#include <nmmintrin.h>
#endif

namespace portico {

namespace {

// The reflected Castagnoli polynomial.
constexpr uint32_t kPolynomial = 0x82F63B78u;

constexpr std::array<uint32_t, 256> makeTable() {
  std::array<uint32_t, 256> table{};
  for (uint32_t byte = 0; byte < 256; ++byte) {
    uint32_t crc = byte;
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (crc & 1 ? kPolynomial : 0);
    table[byte] = crc;
  }
  return table;
}
constexpr std::array<uint32_t, 256> kTable = makeTable();

// Any CPU: a byte at a time (the register holds the complemented CRC).
uint32_t softwareCrc(const unsigned char* bytes, size_t size, uint32_t state) {
  for (size_t i = 0; i < size; ++i) state = (state >> 8) ^ kTable[(state ^ bytes[i]) & 0xFF];
  return state;
}

#if defined(__x86_64__)
// SSE 4.2's crc32 instruction, 8 bytes at a time. The build targets
// baseline x86-64, so the instruction is enabled for this function alone and
// chosen at run time.
[[gnu::target("sse4.2")]] uint32_t hardwareCrc(const unsigned char* bytes, size_t size, uint32_t state) {
  uint64_t wide = state;
  while (size >= 8) {
    uint64_t word;
    std::memcpy(&word, bytes, 8);
    wide = _mm_crc32_u64(wide, word);
    bytes += 8;
    size -= 8;
  }
  uint32_t narrow = uint32_t(wide);
  while (size-- > 0) narrow = _mm_crc32_u8(narrow, *bytes++);
  return narrow;
}

bool hasHardwareCrc() {
  static const bool has = __builtin_cpu_supports("sse4.2");
  return has;
}
#endif

}  // namespace

uint32_t crc32c(const void* data, size_t size, uint32_t crc) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  const uint32_t state = ~crc;
#if defined(__x86_64__)
  if (hasHardwareCrc()) return ~hardwareCrc(bytes, size, state);
#endif
  return ~softwareCrc(bytes, size, state);
}

}  // namespace portico
