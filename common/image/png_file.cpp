#include "common/image/png_file.h"

#include <fmt/format.h>
#include <png.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace portico {

uint8_t toneMapToByte(float radiance, float exposure) {
  float v = radiance * exposure;
  if (!(v > 0.0f)) return 0;   // also maps NaN to black
  v = std::min(v, 1.0f);
  const float srgb = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
  return static_cast<uint8_t>(std::lround(srgb * 255.0f));
}

void writePng(const std::string& path, uint32_t width, uint32_t height, const std::vector<uint8_t>& rgb) {
  if (rgb.size() != size_t(width) * height * 3)
    throw std::runtime_error(fmt::format("image {}: {} bytes for {}x{} RGB pixels", path, rgb.size(), width, height));
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  image.width = width;
  image.height = height;
  image.format = PNG_FORMAT_RGB;
  if (!png_image_write_to_file(&image, path.c_str(), 0, rgb.data(), 0, nullptr))
    throw std::runtime_error(fmt::format("image {}: {}", path, image.message));
}

std::string encodePng(uint32_t width, uint32_t height, const std::vector<uint8_t>& rgb) {
  if (rgb.size() != size_t(width) * height * 3)
    throw std::runtime_error(fmt::format("PNG: {} bytes for {}x{} RGB pixels", rgb.size(), width, height));
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  image.width = width;
  image.height = height;
  image.format = PNG_FORMAT_RGB;
  png_alloc_size_t size = 0;
  // Asked once for the size, then written.
  if (!png_image_write_to_memory(&image, nullptr, &size, 0, rgb.data(), 0, nullptr))
    throw std::runtime_error(fmt::format("PNG: {}", image.message));
  std::string bytes(size, '\0');
  if (!png_image_write_to_memory(&image, bytes.data(), &size, 0, rgb.data(), 0, nullptr))
    throw std::runtime_error(fmt::format("PNG: {}", image.message));
  bytes.resize(size);
  return bytes;
}

}  // namespace portico
