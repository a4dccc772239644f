// A directory under $TMPDIR (else /tmp) for one run's scratch files,
// removed with everything in it when the object goes (unless kept).
#pragma once

#include <filesystem>
#include <string>

namespace portico {

// Creates $TMPDIR/<prefix>-XXXXXX (mode 0700), else under /tmp; throws
// std::runtime_error naming the parent and the reason when it cannot.
std::filesystem::path makeTemporaryDirectory(const std::string& prefix);

class TemporaryDirectory {
 public:
  // makeTemporaryDirectory(prefix).
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
