// 8-bit RGB PNG files through libpng: the rendered image's tone-mapped
// copy, and the pictures `portico` draws itself (plots, plans).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace portico {

// sRGB OETF of clamp(v * exposure) to 8 bits: what a PNG (or JPEG) of
// linear radiance holds.
uint8_t toneMapToByte(float radiance, float exposure);

// rgb: width * height * 3 bytes, row 0 at the top. Throws
// std::runtime_error naming the path and libpng's reason on failure.
void writePng(const std::string& path, uint32_t width, uint32_t height, const std::vector<uint8_t>& rgb);

// The same PNG file's bytes, for a reply (the dashboard's previews).
std::string encodePng(uint32_t width, uint32_t height, const std::vector<uint8_t>& rgb);

}  // namespace portico
