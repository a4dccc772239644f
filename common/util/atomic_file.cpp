#include "common/util/atomic_file.h"

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <system_error>

namespace portico {

void writeFileAtomically(const std::string& path, const std::string& contents) {
  const std::filesystem::path target(path);
  std::error_code error;
  if (target.has_parent_path()) std::filesystem::create_directories(target.parent_path(), error);
  const std::string temporary = path + ".tmp";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out << contents;
    out.flush();
    if (!out) throw std::runtime_error("cannot write " + path);
  }
  std::filesystem::rename(temporary, target, error);
  if (error) throw std::runtime_error("cannot write " + path + ": " + error.message());
}

}  // namespace portico
