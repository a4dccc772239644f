#include "coordinator/file_server.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <vector>

namespace portico {

bool isServableStorePath(const std::string& path) {
  if (path == "scene.db") return true;
  const std::string prefix = "cells/", suffix = ".cell";
  if (path.size() <= prefix.size() + suffix.size() || path.compare(0, prefix.size(), prefix) != 0 ||
      path.compare(path.size() - suffix.size(), suffix.size(), suffix) != 0)
    return false;
  const std::string digits = path.substr(prefix.size(), path.size() - prefix.size() - suffix.size());
  return digits.size() <= 10 && std::all_of(digits.begin(), digits.end(), [](char c) { return std::isdigit(uint8_t(c)); });
}

void serveFileChunk(const std::set<std::string>& stores, wire::FetchFile::Reader request,
                    wire::FileChunk::Builder chunk) {
  const std::string store = request.getStore(), path = request.getPath();
  chunk.setStore(store);
  chunk.setPath(path);
  chunk.setOffset(request.getOffset());
  if (!stores.count(store)) {
    chunk.setError(fmt::format("store {} belongs to no active job", store));
    return;
  }
  if (!isServableStorePath(path)) {
    chunk.setError(fmt::format("{} is not a scene store file (scene.db or cells/<id>.cell)", path));
    return;
  }
  const std::string full = store + "/" + path;
  const int fd = ::open(full.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    chunk.setError(fmt::format("{}: cannot open", full));
    return;
  }
  struct stat info {};
  if (::fstat(fd, &info) != 0) {
    ::close(fd);
    chunk.setError(fmt::format("{}: cannot stat", full));
    return;
  }
  const uint64_t total = uint64_t(info.st_size);
  chunk.setTotalBytes(total);
  const uint64_t offset = std::min<uint64_t>(request.getOffset(), total);
  const size_t length = size_t(std::min<uint64_t>(kFileChunkBytes, total - offset));
  auto data = chunk.initData(unsigned(length));
  size_t done = 0;
  while (done < length) {
    const ssize_t n = ::pread(fd, data.begin() + done, length - done, off_t(offset + done));
    if (n <= 0) break;
    done += size_t(n);
  }
  ::close(fd);
  if (done != length) chunk.setError(fmt::format("{}: short read at byte {}", full, offset + done));
}

}  // namespace portico
