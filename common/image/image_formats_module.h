// The interface of portico_image_formats.so, a module that writes the image
// formats portico has no library of its own for (HDR, TIFF, JPEG) through
// OpenImageIO. It is loaded with dlopen on first use, so that a process
// that writes only EXR and PNG never loads OpenImageIO.
#pragma once

#include <cstddef>
#include <cstdint>

extern "C" {
// Writes width x height RGB pixels to path (the format from its extension):
// floats when isFloat, else bytes. Returns 0, or -1 with a reason in error.
using PorticoWriteImageFn = int (*)(const char* path, uint32_t width, uint32_t height, int isFloat,
                                    const void* pixels, char* error, size_t errorSize);
}

namespace portico {
inline constexpr const char* kImageFormatsModule = "portico_image_formats.so";
inline constexpr const char* kImageFormatsEntry = "portico_write_image";
}  // namespace portico
