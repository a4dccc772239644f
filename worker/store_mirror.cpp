#include "worker/store_mirror.h"

#include <fmt/format.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <system_error>

namespace portico {

namespace fs = std::filesystem;

namespace {

uint64_t fnv64(const std::string& text) {
  uint64_t hash = 0xcbf29ce484222325ull;
  for (unsigned char c : text) hash = (hash ^ c) * 0x100000001b3ull;
  return hash;
}

bool sameContents(const fs::path& a, const fs::path& b) {
  std::error_code error;
  if (!fs::exists(a, error) || !fs::exists(b, error) || fs::file_size(a) != fs::file_size(b)) return false;
  std::ifstream fa(a, std::ios::binary), fb(b, std::ios::binary);
  return std::equal(std::istreambuf_iterator<char>(fa), std::istreambuf_iterator<char>(),
                    std::istreambuf_iterator<char>(fb));
}

}  // namespace

StoreMirror::StoreMirror(std::string cacheDirectory) : root_(std::move(cacheDirectory)) {
  std::error_code error;
  fs::create_directories(root_, error);
  if (error || !fs::is_directory(root_))
    throw std::runtime_error(fmt::format("cache directory {}: cannot create it ({})", root_, error.message()));
}

std::string StoreMirror::localDirectory(const std::string& store) const {
  return (fs::path(root_) / fmt::format("{:016x}", fnv64(store))).string();
}

StoreMirror::StoreState& StoreMirror::state(const std::string& store) { return stores_[store]; }

std::optional<std::string> StoreMirror::missing(const std::string& store, uint32_t cell) {
  StoreState& s = state(store);
  if (!s.catalogueFresh) return std::string("scene.db");
  const fs::path local = localDirectory(store);
  if (!s.catalogue) s.catalogue = std::make_unique<SceneStore>(SceneStore::open(local.string()));
  if (cell >= s.catalogue->cells().size())
    throw std::runtime_error(fmt::format("store {}: no cell {}", store, cell));
  const std::string path = fmt::format("cells/{}.cell", cell);
  std::error_code error;
  const fs::path file = local / path;
  if (!fs::exists(file, error) || fs::file_size(file, error) != s.catalogue->cells()[cell].byteCount) return path;
  // The store's textures (any cell may show them): a file arrives whole or not at all.
  for (const Material& material : s.catalogue->materials())
    if (material.textured() && !fs::exists(local / material.albedoTexture, error)) return material.albedoTexture;
  return std::nullopt;
}

uint64_t StoreMirror::receivedBytes(const std::string& store, const std::string& path) const {
  std::error_code error;
  const fs::path part = fs::path(localDirectory(store)) / (path + ".part");
  const auto size = fs::file_size(part, error);
  return error ? 0 : size;
}

bool StoreMirror::accept(wire::FileChunk::Reader chunk) {
  const std::string store = chunk.getStore(), path = chunk.getPath();
  if (chunk.getError().size())
    throw std::runtime_error(fmt::format("coordinator cannot serve {} of {}: {}", path, store, chunk.getError().cStr()));
  if (path != "scene.db" && path.rfind("cells/", 0) != 0 && path.rfind("textures/", 0) != 0)
    throw std::runtime_error(fmt::format("coordinator sent an unexpected file {}", path));
  const fs::path local = localDirectory(store);
  const fs::path part = local / (path + ".part"), final = local / path;
  fs::create_directories(part.parent_path());
  if (chunk.getOffset() != receivedBytes(store, path))
    throw std::runtime_error(fmt::format("{} of {}: chunk at byte {} but {} bytes received", path, store,
                                         chunk.getOffset(), receivedBytes(store, path)));
  {
    std::ofstream out(part, std::ios::binary | std::ios::app);
    auto data = chunk.getData();
    out.write(reinterpret_cast<const char*>(data.begin()), std::streamsize(data.size()));
    if (!out) throw std::runtime_error(fmt::format("{}: cannot write", part.string()));
    bytesFetched_ += data.size();
  }
  if (receivedBytes(store, path) < chunk.getTotalBytes()) return false;
  StoreState& s = state(store);
  if (path == "scene.db") {
    // A different catalogue means a regenerated store: its old cells go.
    if (!sameContents(part, final)) {
      fs::remove_all(local / "cells");
      fs::remove_all(local / "textures");
    }
    s.catalogue.reset();
    s.catalogueFresh = true;
  }
  fs::rename(part, final);
  return true;
}

}  // namespace portico
