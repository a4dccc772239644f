// Albedo textures at surface points: a material's texture (linear RGB,
// bilinear between texel centres, repeating) times its albedo, read through
// OpenImageIO's TextureSystem in portico_image_formats.so
// (common/image/texture_module.h). The module is loaded on the first lookup
// of a textured material, so untextured scenes never load OpenImageIO.
//
// One TextureSystem serves the whole process: its tile cache holds at most
// cacheBytes() of texels whatever the textures' size (the worker counts it,
// and the module's own code, in its --memory budget). Texels are exact
// values from the file, so a lookup gives the same bits whatever the cache
// holds or in which order lookups come.
#pragma once

#include <cstdint>
#include <string>

#include "common/math.h"
#include "common/scene/store/cell_geometry.h"
#include "common/scene/store/scene_types.h"

namespace portico {

// The default bound of the tile cache, for processes that set none.
inline constexpr uint64_t kDefaultTextureCacheBytes = uint64_t(64) << 20;

class AlbedoTextures {
 public:
  static AlbedoTextures& instance();

  // The tile cache's bound; takes effect when the module is loaded (later
  // calls change nothing).
  void setCacheBytes(uint64_t bytes);
  uint64_t cacheBytes() const { return cacheBytes_; }
  // Loads the module and makes the TextureSystem (done by the first lookup
  // otherwise). Throws std::runtime_error if the module cannot be loaded.
  void load();
  bool loaded() const { return system_ != nullptr; }
  // Bytes the tile cache holds now and has read from texture files (0 before load()).
  uint64_t cacheBytesHeld() const;
  uint64_t bytesRead() const;

  // `material`'s albedo at texture coordinate uv: its albedo when it has no
  // texture. Throws std::runtime_error naming the texture and the material
  // when the texture cannot be read.
  Vec3 albedoAt(const std::string& storeDirectory, const Material& material, Uv uv);

 private:
  AlbedoTextures() = default;
  struct Texture;
  const Texture& texture(const std::string& storeDirectory, const Material& material);

  uint64_t cacheBytes_ = kDefaultTextureCacheBytes;
  void* system_ = nullptr;
};

// The albedo at `point` on `primitive` of `cell` (made of `material`): its
// texture's colour at the point's uv times the albedo, or the albedo.
Vec3 surfaceAlbedo(const std::string& storeDirectory, const CellGeometry& cell, const Material& material,
                   uint32_t primitive, const Vec3& point);

// sRGB-encoded value in [0, 1] -> linear (IEC 61966-2-1).
float srgbToLinear(float encoded);

}  // namespace portico
