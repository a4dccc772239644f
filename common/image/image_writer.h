// Writes a linear RGB float image: EXR keeps radiance as it is; PNG (and
// other 8-bit formats) get exposure, clamping and the sRGB curve. The format
// follows the file name's extension.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace portico {

struct LinearImage {
  uint32_t width = 0, height = 0;
  std::vector<float> rgb;   // row 0 at the top, 3 floats per pixel
};

// Throws std::runtime_error naming the path on failure. The image is written
// to a temporary file beside `path` and renamed, so a reader never sees half a file.
void writeImage(const std::string& path, const LinearImage& image, float exposure = 1.0f);

// Reads any image OpenImageIO reads as linear RGB floats (for tests and comparisons).
LinearImage readImage(const std::string& path);

// sRGB OETF of clamp(v * exposure) to 8 bits.
uint8_t toneMapToByte(float radiance, float exposure);

}  // namespace portico
