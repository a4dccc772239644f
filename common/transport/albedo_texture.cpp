#include "common/transport/albedo_texture.h"

#include <sys/stat.h>

#include <fmt/format.h>

#include <cmath>
#include <map>
#include <mutex>
#include <stdexcept>

#include "common/image/image_formats_loader.h"
#include "common/image/texture_module.h"

namespace portico {

namespace {

struct Entries {
  PorticoTextureSystemCreateFn create;
  PorticoTextureOpenFn open;
  PorticoTextureTexelsFn texels;
  PorticoTextureMemoryFn memory;
};

const Entries& entries() {
  static const Entries loaded{
      reinterpret_cast<PorticoTextureSystemCreateFn>(imageFormatsEntry(kTextureSystemCreateEntry)),
      reinterpret_cast<PorticoTextureOpenFn>(imageFormatsEntry(kTextureOpenEntry)),
      reinterpret_cast<PorticoTextureTexelsFn>(imageFormatsEntry(kTextureTexelsEntry)),
      reinterpret_cast<PorticoTextureMemoryFn>(imageFormatsEntry(kTextureMemoryEntry))};
  return loaded;
}

int64_t wrap(int64_t i, int64_t size) {
  const int64_t r = i % size;
  return r < 0 ? r + size : r;
}

// Barycentric weights (of corners 1 and 2) of `point` in the triangle's plane.
void barycentric(const MeshView& mesh, uint32_t primitive, const Vec3& point, float& b1, float& b2) {
  Vec3 a, b, c;
  mesh.triangle(primitive, a, b, c);
  const Vec3 e1 = b - a, e2 = c - a, p = point - a;
  const float d11 = dot(e1, e1), d12 = dot(e1, e2), d22 = dot(e2, e2);
  const float p1 = dot(p, e1), p2 = dot(p, e2);
  const float denominator = d11 * d22 - d12 * d12;
  if (!(denominator > 0.0f)) {
    b1 = b2 = 0.0f;
    return;
  }
  b1 = (d22 * p1 - d12 * p2) / denominator;
  b2 = (d11 * p2 - d12 * p1) / denominator;
}

std::mutex textureMutex;

}  // namespace

struct AlbedoTextures::Texture {
  void* handle = nullptr;
  PorticoTextureInfo info;
  std::string path;
};

AlbedoTextures& AlbedoTextures::instance() {
  static AlbedoTextures textures;
  return textures;
}

void AlbedoTextures::setCacheBytes(uint64_t bytes) {
  std::lock_guard lock(textureMutex);
  if (!system_) cacheBytes_ = bytes;
}

void AlbedoTextures::load() {
  std::lock_guard lock(textureMutex);
  if (!system_) system_ = entries().create(cacheBytes_);
}

uint64_t AlbedoTextures::cacheBytesHeld() const {
  uint64_t held = 0, read = 0;
  if (system_) entries().memory(system_, &held, &read);
  return held;
}

uint64_t AlbedoTextures::bytesRead() const {
  uint64_t held = 0, read = 0;
  if (system_) entries().memory(system_, &held, &read);
  return read;
}

const AlbedoTextures::Texture& AlbedoTextures::texture(const std::string& storeDirectory, const Material& material) {
  static std::map<std::string, Texture> opened;
  const std::string path = storeDirectory + "/" + material.albedoTexture;
  std::lock_guard lock(textureMutex);
  if (auto it = opened.find(path); it != opened.end()) return it->second;
  if (!system_) system_ = entries().create(cacheBytes_);
  Texture texture;
  texture.path = path;
  char error[512] = "";
  // Not a FIFO or a device: the image library's open would block on one for good.
  if (struct stat info {}; ::stat(path.c_str(), &info) == 0 && !S_ISREG(info.st_mode))
    throw std::runtime_error(fmt::format("texture {} of material '{}': not a regular file", path, material.name));
  texture.handle = entries().open(system_, path.c_str(), &texture.info, error, sizeof error);
  if (!texture.handle || texture.info.width <= 0 || texture.info.height <= 0)
    throw std::runtime_error(fmt::format("texture {} of material '{}': {}", path, material.name, error));
  return opened.emplace(path, texture).first->second;
}

Vec3 AlbedoTextures::albedoAt(const std::string& storeDirectory, const Material& material, Uv uv) {
  if (!material.textured()) return material.albedo;
  const Texture& found = texture(storeDirectory, material);
  const int64_t width = found.info.width, height = found.info.height;
  // Texel centres at half-integers; v runs up from the image's bottom row.
  const double x = double(uv.u) * width - 0.5, y = (1.0 - double(uv.v)) * height - 0.5;
  const double x0 = std::floor(x), y0 = std::floor(y);
  const float fx = static_cast<float>(x - x0), fy = static_cast<float>(y - y0);
  if (!std::isfinite(x0) || !std::isfinite(y0)) return material.albedo;
  const int32_t xs[2] = {static_cast<int32_t>(wrap(static_cast<int64_t>(x0), width)),
                         static_cast<int32_t>(wrap(static_cast<int64_t>(x0) + 1, width))};
  const int32_t ys[2] = {static_cast<int32_t>(wrap(static_cast<int64_t>(y0), height)),
                         static_cast<int32_t>(wrap(static_cast<int64_t>(y0) + 1, height))};
  const int32_t texelX[4] = {xs[0], xs[1], xs[0], xs[1]}, texelY[4] = {ys[0], ys[0], ys[1], ys[1]};
  float rgb[12];
  char error[512] = "";
  if (entries().texels(system_, found.handle, texelX, texelY, 4, rgb, error, sizeof error) != 0)
    throw std::runtime_error(fmt::format("texture {} of material '{}': {}", found.path, material.name, error));
  if (found.info.integerEncoded)
    for (float& value : rgb) value = srgbToLinear(value);
  const float weights[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
  Vec3 colour(0.0f);
  for (int i = 0; i < 4; ++i) colour += Vec3(rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]) * weights[i];
  // A float texture may hold values above 1; a reflectance cannot.
  return min(max(colour * material.albedo, Vec3(0.0f)), Vec3(1.0f));
}

Vec3 surfaceAlbedo(const std::string& storeDirectory, const CellGeometry& cell, const Material& material,
                   uint32_t primitive, const Vec3& point) {
  if (!material.textured() || !cell.uvs()) return material.albedo;
  float b1, b2;
  barycentric(cell.mesh(), primitive, point, b1, b2);
  return AlbedoTextures::instance().albedoAt(storeDirectory, material, cell.uvAt(primitive, b1, b2));
}

float srgbToLinear(float encoded) {
  return encoded <= 0.04045f ? encoded / 12.92f : std::pow((encoded + 0.055f) / 1.055f, 2.4f);
}

}  // namespace portico
