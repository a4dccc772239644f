#include "common/util/no_follow.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

namespace portico {

FileDescriptor::~FileDescriptor() {
  if (fd_ >= 0) ::close(fd_);
}

FileDescriptor& FileDescriptor::operator=(FileDescriptor&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = other.release();
  }
  return *this;
}

namespace {
constexpr int kDirectoryFlags = O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC;

std::string whyNot(int error) {
  return error == ELOOP || error == ENOTDIR ? "a symbolic link (or not a folder)" : std::strerror(error);
}
}  // namespace

FileDescriptor openDirectoryNoFollow(const std::string& absolutePath, std::string& error) {
  const std::filesystem::path path(absolutePath);
  if (!path.is_absolute()) {
    error = fmt::format("{}: not an absolute path", absolutePath);
    return FileDescriptor();
  }
  FileDescriptor current(::open("/", kDirectoryFlags));
  std::filesystem::path walked = "/";
  for (const auto& component : path.relative_path()) {
    const std::string name = component.string();
    if (name.empty() || name == ".") continue;
    walked /= name;
    if (name == "..") {
      error = fmt::format("{}: has a '..' component", absolutePath);
      return FileDescriptor();
    }
    FileDescriptor next(::openat(current.get(), name.c_str(), kDirectoryFlags));
    if (!next.valid()) {
      error = fmt::format("{}: cannot open {}: {}", absolutePath, walked.string(), whyNot(errno));
      return FileDescriptor();
    }
    current = std::move(next);
  }
  return current;
}

FileDescriptor openSubdirectoryNoFollow(int parent, const std::string& name, bool create, std::string& error) {
  if (name.empty() || name == "." || name == ".." || name.find('/') != std::string::npos) {
    error = fmt::format("'{}' is not a folder name", name);
    return FileDescriptor();
  }
  if (create && ::mkdirat(parent, name.c_str(), 0755) != 0 && errno != EEXIST) {
    error = fmt::format("{}: cannot create: {}", name, std::strerror(errno));
    return FileDescriptor();
  }
  FileDescriptor directory(::openat(parent, name.c_str(), kDirectoryFlags));
  if (!directory.valid()) error = fmt::format("{}: cannot open: {}", name, whyNot(errno));
  return directory;
}

}  // namespace portico
