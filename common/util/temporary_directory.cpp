#include "common/util/temporary_directory.h"

#include <stdlib.h>

#include <stdexcept>
#include <system_error>
#include <vector>

namespace portico {

TemporaryDirectory::TemporaryDirectory(const std::string& prefix) {
  const std::string pattern = "/tmp/" + prefix + "-XXXXXX";
  std::vector<char> name(pattern.begin(), pattern.end());
  name.push_back('\0');
  if (!::mkdtemp(name.data())) throw std::runtime_error("cannot create a temporary directory " + pattern);
  path_ = name.data();
}

TemporaryDirectory::~TemporaryDirectory() {
  if (keep_) return;
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

}  // namespace portico
