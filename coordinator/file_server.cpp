#include "coordinator/file_server.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <memory>
#include <cctype>
#include <vector>

#include "common/util/file_at.h"

namespace portico {

namespace {
// "<prefix><digits><suffix>", at most 10 digits.
bool isNumberedFile(const std::string& path, const std::string& prefix, const std::string& suffix) {
  if (path.size() <= prefix.size() + suffix.size() || path.compare(0, prefix.size(), prefix) != 0 ||
      path.compare(path.size() - suffix.size(), suffix.size(), suffix) != 0)
    return false;
  const std::string digits = path.substr(prefix.size(), path.size() - prefix.size() - suffix.size());
  return digits.size() <= 10 && std::all_of(digits.begin(), digits.end(), [](char c) { return std::isdigit(uint8_t(c)); });
}
}  // namespace

bool isServableStorePath(const std::string& path) {
  return path == "scene.db" || isNumberedFile(path, "cells/", ".cell") || isNumberedFile(path, "textures/", ".tif");
}

namespace {
// A file descriptor closed when it goes out of scope.
struct FileDescriptor {
  int fd = -1;
  explicit FileDescriptor(int value) : fd(value) {}
  ~FileDescriptor() {
    if (fd >= 0) ::close(fd);
  }
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
};

// Opens `path` (servable, so "scene.db" or "cells/N.cell") under the store
// directory, component by component, following no symbolic link. Returns
// the descriptor, or -1 with `error` set.
int openInsideStore(const std::string& store, const std::string& path, std::string& error) {
  FileDescriptor directory(::open(store.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC));
  if (directory.fd < 0) {
    error = fmt::format("{}: cannot open the store directory: {}", store, std::strerror(errno));
    return -1;
  }
  int parent = directory.fd;
  std::string name = path;
  std::unique_ptr<FileDescriptor> cells;
  if (const size_t slash = path.find('/'); slash != std::string::npos) {
    cells = std::make_unique<FileDescriptor>(
        ::openat(directory.fd, path.substr(0, slash).c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC));
    if (cells->fd < 0) {
      error = fmt::format("{}/{}: cannot open{}", store, path.substr(0, slash),
                          errno == ELOOP || errno == ENOTDIR ? ": not a directory of the store (a symbolic link?)" : "");
      return -1;
    }
    parent = cells->fd;
    name = path.substr(slash + 1);
  }
  // O_NONBLOCK: a FIFO planted in the store must not stall the coordinator's loop.
  const int fd = ::openat(parent, name.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    error = fmt::format("{}/{}: cannot open{}", store, path,
                        errno == ELOOP ? ": a symbolic link (a store serves only its own regular files)" : "");
    return -1;
  }
  struct stat info {};
  if (::fstat(fd, &info) != 0 || !S_ISREG(info.st_mode)) {
    ::close(fd);
    error = fmt::format("{}/{}: not a regular file", store, path);
    return -1;
  }
  return fd;
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
  FileDescriptor file(openInsideStore(store, path, error));
  if (file.fd < 0) {
    chunk.setError(error);
    return;
  }
  const std::string full = store + "/" + path;
  struct stat info {};
  if (::fstat(file.fd, &info) != 0) {
    chunk.setError(fmt::format("{}: cannot stat", full));
    return;
  }
  const uint64_t total = uint64_t(info.st_size);
  chunk.setTotalBytes(total);
  const uint64_t offset = std::min<uint64_t>(request.getOffset(), total);
  const size_t length = size_t(std::min<uint64_t>(kFileChunkBytes, total - offset));
  auto data = chunk.initData(unsigned(length));
  int readError = 0;
  const size_t done = readAt(file.fd, data.begin(), length, int64_t(offset), readError);
  if (done != length) chunk.setError(fmt::format("{}: short read at byte {}", full, offset + done));
}

}  // namespace portico
