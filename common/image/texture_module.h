// The texture half of portico_image_formats.so (image_formats_module.h):
// albedo textures read through OpenImageIO's TextureSystem, whose tile cache
// holds at most a given number of bytes whatever the textures' size, and the
// import-time copy of a texture into a scene store as a tiled TIFF (so that a
// lookup reads one 64x64 tile, not a whole scanline image). Loaded with
// dlopen only by a process that meets a textured material
// (common/transport/albedo_texture.h, scene_store_writer.cpp).
#pragma once

#include <cstddef>
#include <cstdint>

extern "C" {
struct PorticoTextureInfo {
  int32_t width = 0, height = 0, channels = 0;
  // Stored as integers (8- or 16-bit): sRGB-encoded colours, to be
  // linearised; float and half textures hold linear values.
  int32_t integerEncoded = 0;
};

// Writes `source` (any format OpenImageIO reads) to `target` as a tiled TIFF
// with the same pixels, channels and pixel type. Returns 0, or -1 with a
// reason in error.
using PorticoTextureConvertFn = int (*)(const char* source, const char* target, char* error, size_t errorSize);
// A TextureSystem of its own whose tile cache holds at most maxMemoryBytes.
using PorticoTextureSystemCreateFn = void* (*)(uint64_t maxMemoryBytes);
// The texture's handle (valid as long as the system), with its size; null
// with a reason in error when it cannot be read.
using PorticoTextureOpenFn = void* (*)(void* system, const char* path, PorticoTextureInfo* info, char* error,
                                       size_t errorSize);
// Texels (x[i], y[i]) of level 0 for i < count (at most 4), RGB each (a grey
// texture's value repeated) into rgb[3 * i ...]. Returns 0, or -1 with a
// reason in error.
using PorticoTextureTexelsFn = int (*)(void* system, void* texture, const int32_t* x, const int32_t* y, int count,
                                       float* rgb, char* error, size_t errorSize);
// Bytes the system's tile cache holds now, and bytes it has read from files.
using PorticoTextureMemoryFn = void (*)(void* system, uint64_t* held, uint64_t* read);
}

namespace portico {
inline constexpr const char* kTextureConvertEntry = "portico_texture_convert";
inline constexpr const char* kTextureSystemCreateEntry = "portico_texture_system_create";
inline constexpr const char* kTextureOpenEntry = "portico_texture_open";
inline constexpr const char* kTextureTexelsEntry = "portico_texture_texels";
inline constexpr const char* kTextureMemoryEntry = "portico_texture_memory";
}  // namespace portico
