#include "common/image/image_writer.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <vector>

#include "common/image/exr_file.h"
#include "common/image/image_formats_loader.h"
#include "common/image/image_formats_module.h"
#include "common/image/png_file.h"

namespace portico {

namespace {
std::string lowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

bool isHighDynamicRange(const std::string& ext) {
  return ext == ".exr" || ext == ".hdr" || ext == ".tif" || ext == ".tiff";
}

PorticoWriteImageFn imageFormatsModule() {
  return reinterpret_cast<PorticoWriteImageFn>(imageFormatsEntry(kImageFormatsEntry));
}

void writeWithModule(const std::string& path, const LinearImage& image, bool isFloat, const void* pixels) {
  char error[512] = "";
  if (imageFormatsModule()(path.c_str(), image.width, image.height, isFloat ? 1 : 0, pixels, error, sizeof error) != 0)
    throw std::runtime_error(fmt::format("image {}: {}", path, error));
}
}  // namespace

void writeImage(const std::string& path, const LinearImage& image, float exposure) {
  if (image.rgb.size() != size_t(image.width) * image.height * 3)
    throw std::runtime_error(fmt::format("image {}: {} values for {}x{} pixels", path, image.rgb.size(),
                                         image.width, image.height));
  const std::filesystem::path target(path);
  // Keep the extension on the temporary name: it says the format.
  const std::filesystem::path temporary =
      target.parent_path() / (".tmp-" + target.stem().string() + target.extension().string());
  const std::string ext = lowerExtension(path);
  try {
    if (ext == ".exr") {
      writeExr(temporary.string(), image);
    } else if (isHighDynamicRange(ext)) {
      writeWithModule(temporary.string(), image, true, image.rgb.data());
    } else {
      std::vector<uint8_t> bytes(image.rgb.size());
      for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = toneMapToByte(image.rgb[i], exposure);
      if (ext == ".png")
        writePng(temporary.string(), image.width, image.height, bytes);
      else
        writeWithModule(temporary.string(), image, false, bytes.data());
    }
  } catch (const std::exception& e) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    // Name the file the user asked for, not the temporary one.
    std::string message = e.what();
    for (size_t at = message.find(temporary.string()); at != std::string::npos;
         at = message.find(temporary.string(), at + path.size()))
      message.replace(at, temporary.string().size(), path);
    throw std::runtime_error(message);
  }
  std::filesystem::rename(temporary, target);
}

}  // namespace portico
