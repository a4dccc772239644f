// Writes a linear RGB float image: EXR (and HDR, TIFF) keep radiance as it
// is; PNG (and JPEG) get exposure, clamping and the sRGB curve. The format
// follows the file name's extension. EXR and PNG are written by their own
// libraries; the other formats by OpenImageIO, which is loaded (from
// portico_image_formats.so beside the program) only when one is asked for:
// it costs a process ~0.5 s of start-up.
#pragma once

#include <cstdint>
#include <string>

#include "common/image/linear_image.h"
#include "common/image/png_file.h"   // toneMapToByte

namespace portico {

// Throws std::runtime_error naming the path on failure. The image is written
// to a temporary file beside `path` and renamed, so a reader never sees half a file.
void writeImage(const std::string& path, const LinearImage& image, float exposure = 1.0f);

}  // namespace portico
