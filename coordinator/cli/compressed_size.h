// How small a file gets under zlib: the "compressed" column of the paper's
// Table 2, reported by `portico scene info`.
#pragma once

#include <cstdint>
#include <string>

namespace portico::cli {

// The size of `path` deflated by zlib at its default level. The file is read
// and compressed in 1 MiB chunks and the output is counted, not kept, so a
// cell file of several GB needs no more memory. Throws std::runtime_error
// naming the file when it cannot be read.
uint64_t zlibCompressedSize(const std::string& path);

}  // namespace portico::cli
