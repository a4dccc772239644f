// The texture entries of portico_image_formats.so: see texture_module.h.
#include "common/image/texture_module.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/texture.h>

#include <algorithm>
#include <cstdio>
#include <string>

namespace {

constexpr int kTileSize = 64;

int fail(char* error, size_t errorSize, const std::string& reason) {
  std::snprintf(error, errorSize, "%s", reason.c_str());
  return -1;
}

bool integerEncoded(OIIO::TypeDesc format) {
  return format.basetype != OIIO::TypeDesc::FLOAT && format.basetype != OIIO::TypeDesc::HALF &&
         format.basetype != OIIO::TypeDesc::DOUBLE;
}

}  // namespace

#define PORTICO_EXPORT extern "C" __attribute__((visibility("default")))

PORTICO_EXPORT int portico_texture_convert(const char* source, const char* target, char* error, size_t errorSize) {
  OIIO::ImageBuf image(source);
  if (!image.read(0, 0, true)) return fail(error, errorSize, "cannot read: " + image.geterror());
  if (image.spec().width <= 0 || image.spec().height <= 0 || image.spec().nchannels <= 0)
    return fail(error, errorSize, "has no pixels");
  image.set_write_format(image.spec().format);
  image.set_write_tiles(kTileSize, kTileSize);
  if (!image.write(target, OIIO::TypeUnknown, "tiff"))
    return fail(error, errorSize, "cannot write " + std::string(target) + ": " + image.geterror());
  return 0;
}

PORTICO_EXPORT void* portico_texture_system_create(uint64_t maxMemoryBytes) {
  OIIO::TextureSystem* system = OIIO::TextureSystem::create(false);
  system->attribute("max_memory_MB", static_cast<float>(static_cast<double>(maxMemoryBytes) / (1024.0 * 1024.0)));
  system->attribute("autotile", kTileSize);   // textures not written by the importer stay bounded too
  system->attribute("automip", 0);
  system->attribute("max_open_files", 32);
  return system;
}

PORTICO_EXPORT void* portico_texture_open(void* system, const char* path, PorticoTextureInfo* info, char* error,
                                          size_t errorSize) {
  auto* textures = static_cast<OIIO::TextureSystem*>(system);
  OIIO::TextureSystem::TextureHandle* handle = textures->get_texture_handle(OIIO::ustring(path));
  const OIIO::ImageSpec* spec = handle ? textures->imagespec(handle, nullptr, 0) : nullptr;
  if (!spec) {
    fail(error, errorSize, "cannot read: " + textures->geterror());
    return nullptr;
  }
  info->width = spec->width;
  info->height = spec->height;
  info->channels = spec->nchannels;
  info->integerEncoded = integerEncoded(spec->format) ? 1 : 0;
  return handle;
}

PORTICO_EXPORT int portico_texture_texels(void* system, void* texture, const int32_t* x, const int32_t* y, int count,
                                          float* rgb, char* error, size_t errorSize) {
  auto* textures = static_cast<OIIO::TextureSystem*>(system);
  auto* handle = static_cast<OIIO::TextureSystem::TextureHandle*>(texture);
  OIIO::TextureOpt options;
  const OIIO::ImageSpec* spec = textures->imagespec(handle, nullptr, 0);
  const int channels = spec ? std::min(spec->nchannels, 3) : 0;
  for (int i = 0; i < count; ++i) {
    float value[3] = {0.0f, 0.0f, 0.0f};
    if (channels == 0 || !textures->get_texels(handle, nullptr, options, 0, x[i], x[i] + 1, y[i], y[i] + 1, 0, 1, 0,
                                               channels, OIIO::TypeDesc::FLOAT, value))
      return fail(error, errorSize, "cannot read texel: " + textures->geterror());
    for (int c = 0; c < 3; ++c) rgb[3 * i + c] = value[channels == 3 ? c : 0];
  }
  return 0;
}

PORTICO_EXPORT void portico_texture_memory(void* system, uint64_t* held, uint64_t* read) {
  auto* textures = static_cast<OIIO::TextureSystem*>(system);
  long long used = 0, bytesRead = 0;
  textures->getattribute("stat:cache_memory_used", OIIO::TypeDesc::INT64, &used);
  textures->getattribute("stat:bytes_read", OIIO::TypeDesc::INT64, &bytesRead);
  *held = static_cast<uint64_t>(used);
  *read = static_cast<uint64_t>(bytesRead);
}
