// portico_image_formats.so: see image_formats_module.h.
#include "common/image/image_formats_module.h"

#include <OpenImageIO/imageio.h>

#include <cstdio>
#include <string>

extern "C" __attribute__((visibility("default"))) int portico_write_image(const char* path, uint32_t width,
                                                                           uint32_t height, int isFloat,
                                                                           const void* pixels, char* error,
                                                                           size_t errorSize) {
  const auto fail = [&](const std::string& reason) {
    std::snprintf(error, errorSize, "%s", reason.c_str());
    return -1;
  };
  auto out = OIIO::ImageOutput::create(path);
  if (!out) return fail("unsupported format (" + OIIO::geterror() + ")");
  const OIIO::TypeDesc type = isFloat ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8;
  OIIO::ImageSpec spec(static_cast<int>(width), static_cast<int>(height), 3, type);
  if (!out->open(path, spec)) return fail("cannot open for writing: " + out->geterror());
  if (!out->write_image(type, pixels) || !out->close()) return fail("write failed: " + out->geterror());
  return 0;
}
