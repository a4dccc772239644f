// Opening paths without following symbolic links, one component at a time
// (openat), so that no folder on the way can be swapped for a link to
// somewhere else: the coordinator's file server (a store's path, resolved at
// submit) and a --cache-dir worker's writes (under its cache directory).
#pragma once

#include <string>

namespace portico {

// A file descriptor closed when it goes out of scope.
class FileDescriptor {
 public:
  explicit FileDescriptor(int fd = -1) : fd_(fd) {}
  ~FileDescriptor();
  FileDescriptor(FileDescriptor&& other) noexcept : fd_(other.release()) {}
  FileDescriptor& operator=(FileDescriptor&& other) noexcept;
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  int get() const { return fd_; }
  bool valid() const { return fd_ >= 0; }
  int release() {
    const int fd = fd_;
    fd_ = -1;
    return fd;
  }

 private:
  int fd_;
};

// Opens the directory at `absolutePath` from "/" down, refusing a symbolic
// link anywhere on the way. Invalid, with `error` set ("PATH: a symbolic
// link at COMPONENT" or the system's reason), when it cannot.
FileDescriptor openDirectoryNoFollow(const std::string& absolutePath, std::string& error);

// The directory `name` (one component, no '/') under `parent`, created
// (mode 0755) when `create` and missing; never a symbolic link.
FileDescriptor openSubdirectoryNoFollow(int parent, const std::string& name, bool create, std::string& error);

}  // namespace portico
