// Fuzz target: a scene store catalogue. The input is written as scene.db in
// a temporary directory and opened with SceneStore::open, as the coordinator
// and the workers do.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "common/scene/store/scene_store.h"

using namespace portico;
namespace fs = std::filesystem;

namespace {
// Removed when libFuzzer exits (it calls exit(), so static destructors run).
struct TemporaryDirectory {
  fs::path path;
  ~TemporaryDirectory() {
    std::error_code ignored;
    fs::remove_all(path, ignored);
  }
};

const fs::path& storeDirectory() {
  static const TemporaryDirectory dir{[] {
    const fs::path base = fs::exists("/dev/shm") ? fs::path("/dev/shm") : fs::temp_directory_path();
    fs::path d = base / ("portico-fuzz-store-" + std::to_string(getpid()));
    fs::create_directories(d);
    return d;
  }()};
  return dir.path;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const fs::path& dir = storeDirectory();
  // A header claiming WAL or a hot journal makes SQLite look for side files:
  // none may survive from the previous input.
  for (const char* side : {"scene.db-wal", "scene.db-shm", "scene.db-journal"}) fs::remove(dir / side);
  {
    std::ofstream out(dir / "scene.db", std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    if (!out) __builtin_trap();
  }
  try {
    const SceneStore store = SceneStore::open(dir.string());
    (void)store.totalTriangles();
    (void)store.locateCell(store.camera().origin);
    if (!store.cells().empty()) (void)store.cellPath(0);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
