#include "common/util/temporary_directory.h"

#include <stdlib.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <system_error>

namespace portico {

std::filesystem::path makeTemporaryDirectory(const std::string& prefix) {
  const char* const tmpdir = std::getenv("TMPDIR");
  const std::filesystem::path parent = tmpdir && *tmpdir ? tmpdir : "/tmp";
  std::string name = (parent / (prefix + "-XXXXXX")).string();
  if (!::mkdtemp(name.data()))
    throw std::runtime_error("cannot create a temporary directory under " + parent.string() + ": " +
                             std::strerror(errno));
  return name;
}

TemporaryDirectory::TemporaryDirectory(const std::string& prefix) : path_(makeTemporaryDirectory(prefix)) {}

TemporaryDirectory::~TemporaryDirectory() {
  if (keep_) return;
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

}  // namespace portico
