#include "common/image/image_reader.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>
#include <vector>

namespace portico {

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
