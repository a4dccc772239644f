// Peer renderers beside portico in `portico bench quality`: Mitsuba 3's path
// tracer and LuxCoreRender (its path tracer, optionally with its PhotonGI
// cache), each run as a Python module of the sources (python/portico_mitsuba
// for reference scenes, python/portico_peers for a scene store's camera),
// one render per sample count, timed by the module itself.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace portico::cli {

struct PeerRender {
  uint32_t spp = 0;
  double seconds = 0;   // the render alone: scene loading and JIT compilation excluded
  std::filesystem::path image;
};

// $MITSUBA_VENV/bin/python, else ~/.local/share/portico/mitsuba-venv/bin/python
// (where deploy/install-deps.sh --peers puts it).
std::string defaultMitsubaPython();

// Renders a reference scene (scene.json) at each of `sppList` (comma-separated)
// on `threads` threads into `outDirectory`. Throws std::runtime_error, naming
// the interpreter or the log, when Mitsuba is not installed or a render fails.
std::vector<PeerRender> renderWithMitsuba(const std::string& sceneDirectory, const std::string& sppList,
                                          uint32_t threads, const std::string& python,
                                          const std::filesystem::path& outDirectory);

// Writes `camera` of the scene store (its geometry by material, as PLY) into
// `viewDirectory` for the peers below; width/height 0 keep the camera's.
void writePeerView(const std::string& portico, const std::string& store, const std::string& camera, uint32_t width,
                   uint32_t height, const std::filesystem::path& viewDirectory);

// The view of writePeerView rendered by Mitsuba 3 (two-sided diffuse surfaces).
std::vector<PeerRender> renderViewWithMitsuba(const std::filesystem::path& viewDirectory, const std::string& sppList,
                                              uint32_t threads, const std::string& python);

// The view rendered by LuxCoreRender (pyluxcore in the sources' .venv);
// photonGi > 0: with a PhotonGI indirect cache of at most that many photons.
std::vector<PeerRender> renderViewWithLuxcore(const std::filesystem::path& viewDirectory, const std::string& sppList,
                                              uint32_t threads, uint64_t photonGi);

}  // namespace portico::cli
