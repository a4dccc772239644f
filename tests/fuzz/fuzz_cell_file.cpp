// Fuzz target: a cell file, written to a temporary file and opened with the
// reader the worker uses (CellGeometry::load: mmap + Cap'n Proto + checks).
#include <fcntl.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "common/scene/store/cell_geometry.h"

using namespace portico;

namespace {
// The seeds are cells/0.cell files; a store of this many materials.
constexpr uint32_t kExpectedCell = 0;
constexpr size_t kMaterialCount = 64;

// Removed when libFuzzer exits (it calls exit(), so static destructors run).
struct TemporaryFile {
  std::string path;
  ~TemporaryFile() { ::unlink(path.c_str()); }
};

const std::string& cellPath() {
  static const TemporaryFile file{[] {
    // /dev/shm when there is one: a file per execution, a million times.
    const std::filesystem::path base =
        std::filesystem::exists("/dev/shm") ? std::filesystem::path("/dev/shm") : std::filesystem::temp_directory_path();
    return (base / ("portico-fuzz-cell-" + std::to_string(getpid()) + ".cell")).string();
  }()};
  return file.path;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string& path = cellPath();
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0 || ::write(fd, data, size) != static_cast<ssize_t>(size)) __builtin_trap();
  ::close(fd);
  try {
    const auto cell = CellGeometry::load(path, kExpectedCell, kMaterialCount);
    // What an accelerator build reads next: every triangle's vertices and material.
    float sum = 0;
    for (uint64_t t = 0; t < cell->mesh().triangleCount; ++t) {
      for (int corner = 0; corner < 3; ++corner) sum += cell->mesh().positions[3 * cell->mesh().indices[3 * t + corner]];
      sum += float(cell->material(static_cast<uint32_t>(t)));
    }
    for (const auto& portal : cell->portals()) sum += portal.polygon.front().x;
    (void)sum;
  } catch (const std::runtime_error&) {
  }
  return 0;
}
