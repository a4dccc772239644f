// Mitsuba 3's path tracer on a reference scene, for `portico bench quality
// --mitsuba`: runs python/portico_mitsuba in the virtual environment
// deploy/install-deps.sh --mitsuba makes, one render per sample count.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace portico::cli {

struct MitsubaRender {
  uint32_t spp = 0;
  double seconds = 0;   // the render alone: scene loading and JIT compilation excluded
  std::filesystem::path image;
};

// $MITSUBA_VENV/bin/python, else ~/.local/share/portico/mitsuba-venv/bin/python
// (where deploy/install-deps.sh --mitsuba puts it).
std::string defaultMitsubaPython();

// Renders `sceneDirectory` at each of `sppList` (comma-separated) on
// `threads` threads into `outDirectory`. Throws std::runtime_error, naming
// the interpreter or the log, when Mitsuba is not installed or a render fails.
std::vector<MitsubaRender> renderWithMitsuba(const std::string& sceneDirectory, const std::string& sppList,
                                             uint32_t threads, const std::string& python,
                                             const std::filesystem::path& outDirectory);

}  // namespace portico::cli
