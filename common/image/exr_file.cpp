#include "common/image/exr_file.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <fmt/format.h>

#include <stdexcept>

namespace portico {

void writeExr(const std::string& path, const LinearImage& image) {
  try {
    Imf::Header header(static_cast<int>(image.width), static_cast<int>(image.height));
    header.compression() = Imf::ZIP_COMPRESSION;
    Imf::FrameBuffer frame;
    const char* names[3] = {"R", "G", "B"};
    // The library takes a non-const base pointer, but only reads when writing.
    char* base = reinterpret_cast<char*>(const_cast<float*>(image.rgb.data()));
    const size_t pixelBytes = 3 * sizeof(float);
    for (int c = 0; c < 3; ++c) {
      header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
      frame.insert(names[c], Imf::Slice(Imf::FLOAT, base + c * sizeof(float), pixelBytes, pixelBytes * image.width));
    }
    Imf::OutputFile file(path.c_str(), header);
    file.setFrameBuffer(frame);
    file.writePixels(static_cast<int>(image.height));
  } catch (const std::exception& e) {
    throw std::runtime_error(fmt::format("image {}: {}", path, e.what()));
  }
}

}  // namespace portico
