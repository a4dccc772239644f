// 8-bit RGB PNG files through libpng: the rendered image's tone-mapped
// copy, and the pictures `portico` draws itself (plots, plans).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace portico {

// rgb: width * height * 3 bytes, row 0 at the top. Throws
// std::runtime_error naming the path and libpng's reason on failure.
void writePng(const std::string& path, uint32_t width, uint32_t height, const std::vector<uint8_t>& rgb);

}  // namespace portico
