#include "common/image/image_writer.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

namespace portico {

namespace {
bool isHighDynamicRange(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".exr" || ext == ".hdr" || ext == ".tif" || ext == ".tiff";
}
}  // namespace

uint8_t toneMapToByte(float radiance, float exposure) {
  float v = radiance * exposure;
  if (!(v > 0.0f)) return 0;   // also maps NaN to black
  v = std::min(v, 1.0f);
  const float srgb = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
  return static_cast<uint8_t>(std::lround(srgb * 255.0f));
}

void writeImage(const std::string& path, const LinearImage& image, float exposure) {
  if (image.rgb.size() != size_t(image.width) * image.height * 3)
    throw std::runtime_error(fmt::format("image {}: {} values for {}x{} pixels", path, image.rgb.size(),
                                         image.width, image.height));
  const std::filesystem::path target(path);
  // Keep the extension on the temporary name: OpenImageIO picks the format from it.
  const std::filesystem::path temporary =
      target.parent_path() / (".tmp-" + target.stem().string() + target.extension().string());
  auto out = OIIO::ImageOutput::create(path);
  if (!out) throw std::runtime_error(fmt::format("image {}: unsupported format ({})", path, OIIO::geterror()));
  const bool hdr = isHighDynamicRange(path);
  OIIO::ImageSpec spec(image.width, image.height, 3, hdr ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
  if (hdr) spec.attribute("compression", "zip");
  if (!out->open(temporary.string(), spec))
    throw std::runtime_error(fmt::format("image {}: cannot open for writing: {}", path, out->geterror()));
  bool ok;
  if (hdr) {
    ok = out->write_image(OIIO::TypeDesc::FLOAT, image.rgb.data());
  } else {
    std::vector<uint8_t> bytes(image.rgb.size());
    for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = toneMapToByte(image.rgb[i], exposure);
    ok = out->write_image(OIIO::TypeDesc::UINT8, bytes.data());
  }
  ok = ok && out->close();
  if (!ok) {
    std::filesystem::remove(temporary);
    throw std::runtime_error(fmt::format("image {}: write failed: {}", path, out->geterror()));
  }
  std::filesystem::rename(temporary, target);
}

LinearImage readImage(const std::string& path) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) throw std::runtime_error(fmt::format("image {}: cannot read: {}", path, OIIO::geterror()));
  const OIIO::ImageSpec& spec = in->spec();
  LinearImage image;
  image.width = spec.width;
  image.height = spec.height;
  std::vector<float> all(size_t(spec.width) * spec.height * spec.nchannels);
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, all.data()))
    throw std::runtime_error(fmt::format("image {}: read failed: {}", path, in->geterror()));
  image.rgb.resize(size_t(spec.width) * spec.height * 3);
  for (size_t p = 0; p < size_t(spec.width) * spec.height; ++p)
    for (int c = 0; c < 3; ++c) image.rgb[p * 3 + c] = all[p * spec.nchannels + std::min(c, spec.nchannels - 1)];
  return image;
}

}  // namespace portico
