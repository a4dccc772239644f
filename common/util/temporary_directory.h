// A directory under /tmp for one run's scratch files, removed with
// everything in it when the object goes (unless kept).
#pragma once

#include <filesystem>
#include <string>

namespace portico {

class TemporaryDirectory {
 public:
  // Creates /tmp/<prefix>-XXXXXX; throws std::runtime_error when it cannot.
  explicit TemporaryDirectory(const std::string& prefix);
  ~TemporaryDirectory();
  TemporaryDirectory(const TemporaryDirectory&) = delete;
  TemporaryDirectory& operator=(const TemporaryDirectory&) = delete;

  const std::filesystem::path& path() const { return path_; }
  // Leave it on disk (for a user who asked to keep logs).
  void keep() { keep_ = true; }

 private:
  std::filesystem::path path_;
  bool keep_ = false;
};

}  // namespace portico
