// Parses byte sizes a user types: "512MiB", "4GiB", "1.5G", "1000000".
#pragma once

#include <cstdint>
#include <string>

namespace portico {
// Throws std::invalid_argument naming the text.
uint64_t parseByteSize(const std::string& text);
}  // namespace portico
