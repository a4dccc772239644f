#include "worker/store_mirror.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <system_error>

#include "common/scene/store/store_file_names.h"
#include "common/util/file_at.h"
#include "common/util/no_follow.h"

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
  struct stat info {};
  const fs::path part = fs::path(localDirectory(store)) / (path + ".part");
  // Not followed: a link planted there is refused when written, not measured.
  return ::lstat(part.c_str(), &info) == 0 && S_ISREG(info.st_mode) ? uint64_t(info.st_size) : 0;
}

namespace {
// The folder a store file goes into under the store's cache folder (created,
// never a symbolic link) and its name there. `path` is a store file name
// (isServableStorePath): one folder at most.
FileDescriptor openParentFolder(int storeFolder, const std::string& path, std::string& name, std::string& error) {
  const size_t slash = path.find('/');
  if (slash == std::string::npos) {
    name = path;
    return FileDescriptor(::dup(storeFolder));
  }
  name = path.substr(slash + 1);
  return openSubdirectoryNoFollow(storeFolder, path.substr(0, slash), true, error);
}
}  // namespace

bool StoreMirror::accept(wire::FileChunk::Reader chunk) {
  const std::string store = chunk.getStore(), path = chunk.getPath();
  if (chunk.getError().size())
    throw std::runtime_error(fmt::format("coordinator cannot serve {} of {}: {}", path, store, chunk.getError().cStr()));
  // Whatever answers on the endpoint names the file: only a store's own
  // file names are written, and only under the cache directory.
  if (!isServableStorePath(path))
    throw std::runtime_error(fmt::format("coordinator sent '{}', not a scene store file name (scene.db, "
                                         "cells/<id>.cell, textures/<id>.tif): not written",
                                         path));
  const fs::path local = localDirectory(store);
  if (chunk.getOffset() != receivedBytes(store, path))
    throw std::runtime_error(fmt::format("{} of {}: chunk at byte {} but {} bytes received", path, store,
                                         chunk.getOffset(), receivedBytes(store, path)));
  std::string error, name;
  FileDescriptor root(::open(root_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  FileDescriptor storeFolder;
  if (root.valid()) storeFolder = openSubdirectoryNoFollow(root.get(), local.filename().string(), true, error);
  FileDescriptor folder;
  if (storeFolder.valid()) folder = openParentFolder(storeFolder.get(), path, name, error);
  if (!folder.valid())
    throw std::runtime_error(fmt::format("cache directory {}: {}", root_, error.empty() ? std::strerror(errno) : error));
  const std::string partName = name + ".part";
  {
    FileDescriptor out(::openat(folder.get(), partName.c_str(), O_WRONLY | O_CREAT | O_NOFOLLOW | O_CLOEXEC,
                                0644));
    auto data = chunk.getData();
    int writeError = 0;
    if (!out.valid() || writeAt(out.get(), data.begin(), data.size(), int64_t(chunk.getOffset()), writeError) !=
                            data.size())
      throw std::runtime_error(fmt::format("{}: cannot write: {}", (local / (path + ".part")).string(),
                                           std::strerror(out.valid() ? writeError : errno)));
    bytesFetched_ += data.size();
  }
  if (receivedBytes(store, path) < chunk.getTotalBytes()) return false;
  StoreState& s = state(store);
  const fs::path part = local / (path + ".part"), final = local / path;
  if (path == "scene.db") {
    // A different catalogue means a regenerated store: its old cells go.
    if (!sameContents(part, final)) {
      fs::remove_all(local / "cells");
      fs::remove_all(local / "textures");
    }
    s.catalogue.reset();
    s.catalogueFresh = true;
  }
  if (::renameat(folder.get(), partName.c_str(), folder.get(), name.c_str()) != 0)
    throw std::runtime_error(fmt::format("{}: cannot rename into place: {}", final.string(), std::strerror(errno)));
  return true;
}

}  // namespace portico
