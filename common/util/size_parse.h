// Parses byte sizes a user types: "512MiB", "4GiB", "1.5G", "1000000".
#pragma once

#include <cstdint>
#include <string>

namespace portico {
// The largest size accepted: 1 PiB, beyond any machine's memory or disk.
constexpr uint64_t kMaxByteSize = uint64_t(1) << 50;
// Throws std::invalid_argument naming the text.
uint64_t parseByteSize(const std::string& text);
}  // namespace portico
