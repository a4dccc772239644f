#include "coordinator/file_server.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <vector>

#include "common/util/file_at.h"
#include "common/util/no_follow.h"

namespace portico {

namespace {
// Opens `path` (servable, so "scene.db", "cells/N.cell" or "textures/N.tif")
// under the store directory, following no symbolic link from "/" down: the
// store's path was resolved at submit, and a folder above it swapped for a
// link since then (by whoever may write there) must not lead elsewhere.
// Returns the descriptor, invalid with `error` set.
FileDescriptor openInsideStore(const std::string& store, const std::string& path, std::string& error) {
  FileDescriptor directory = openDirectoryNoFollow(store, error);
  if (!directory.valid()) {
    error = fmt::format("cannot open the store directory: {} (its path was resolved at submit)", error);
    return directory;
  }
  std::string name = path;
  if (const size_t slash = path.find('/'); slash != std::string::npos) {
    std::string why;
    directory = openSubdirectoryNoFollow(directory.get(), path.substr(0, slash), false, why);
    if (!directory.valid()) {
      error = fmt::format("{}/{}: cannot open{}", store, path.substr(0, slash),
                          why.find("symbolic link") != std::string::npos
                              ? ": not a directory of the store (a symbolic link?)"
                              : "");
      return directory;
    }
    name = path.substr(slash + 1);
  }
  // O_NONBLOCK: a FIFO planted in the store must not stall the coordinator's loop.
  FileDescriptor file(::openat(directory.get(), name.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC));
  if (!file.valid()) {
    error = fmt::format("{}/{}: cannot open{}", store, path,
                        errno == ELOOP ? ": a symbolic link (a store serves only its own regular files)" : "");
    return file;
  }
  struct stat info {};
  if (::fstat(file.get(), &info) != 0 || !S_ISREG(info.st_mode)) {
    error = fmt::format("{}/{}: not a regular file", store, path);
    return FileDescriptor();
  }
  return file;
}
}  // namespace

void serveFileChunk(const std::set<std::string>& stores, wire::FetchFile::Reader request,
                    wire::FileChunk::Builder chunk) {
  const std::string store = request.getStore(), path = request.getPath();
  chunk.setStore(store);
  chunk.setPath(path);
  chunk.setOffset(request.getOffset());
  if (!stores.count(store)) {
    chunk.setError(fmt::format("store {} belongs to no active job this worker holds a lease of", store));
    return;
  }
  if (!isServableStorePath(path)) {
    chunk.setError(
        fmt::format("{} is not a scene store file (scene.db, cells/<id>.cell or textures/<id>.tif)", path));
    return;
  }
  std::string error;
  FileDescriptor file = openInsideStore(store, path, error);
  if (!file.valid()) {
    chunk.setError(error);
    return;
  }
  const std::string full = store + "/" + path;
  struct stat info {};
  if (::fstat(file.get(), &info) != 0) {
    chunk.setError(fmt::format("{}: cannot stat", full));
    return;
  }
  const uint64_t total = uint64_t(info.st_size);
  chunk.setTotalBytes(total);
  const uint64_t offset = std::min<uint64_t>(request.getOffset(), total);
  const size_t length = size_t(std::min<uint64_t>(kFileChunkBytes, total - offset));
  auto data = chunk.initData(unsigned(length));
  int readError = 0;
  const size_t done = readAt(file.get(), data.begin(), length, int64_t(offset), readError);
  if (done != length) chunk.setError(fmt::format("{}: short read at byte {}", full, offset + done));
}

}  // namespace portico
