// CRC-32C (Castagnoli), the checksum of the coordinator's append-only files
// (coordinator/append_files.h). Chosen over zlib's CRC-32 because x86-64's
// SSE 4.2 computes it in hardware: ~8 bytes a cycle-group instead of zlib's
// table walk, and the coordinator checksums every photon and queued ray it
// stores (~130 MB per million photons), on the thread that dispatches leases.
#pragma once

#include <cstddef>
#include <cstdint>

namespace portico {

// The CRC-32C of `size` bytes at `data`, continuing from `crc` (0 to start):
// crc32c(b, crc32c(a)) == crc32c(a followed by b).
uint32_t crc32c(const void* data, size_t size, uint32_t crc = 0);

}  // namespace portico
