#include "common/image/png_file.h"

#include <fmt/format.h>
#include <png.h>

#include <stdexcept>

namespace portico {

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

}  // namespace portico
