// Whole positional reads and writes: pread/pwrite until every byte is done,
// retrying interrupted calls. Shared by the coordinator's append-only files
// and the workers' deposit regions, which write the same photon files.
#pragma once

#include <cstddef>
#include <cstdint>

namespace portico {

// Reads [offset, offset + size) into `out`; returns the bytes read. Fewer
// means the file ended (`error` 0) or a call failed (`error` its errno).
size_t readAt(int descriptor, void* out, size_t size, int64_t offset, int& error);

// Writes `size` bytes at `offset`; returns the bytes written. Fewer means a
// call failed (`error` its errno, ENOSPC when a call wrote nothing).
size_t writeAt(int descriptor, const void* data, size_t size, int64_t offset, int& error);

}  // namespace portico
