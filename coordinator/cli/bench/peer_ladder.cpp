#include "coordinator/cli/bench/peer_ladder.h"

#include <fmt/format.h>

#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>

#include "common/util/child_process.h"
#include "common/util/project_python.h"
#include "coordinator/cli/python_modules.h"

namespace portico::cli {

namespace fs = std::filesystem;

namespace {

std::string readAll(const fs::path& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Runs one peer's ladder to its end and reads its rows, "spp,seconds,image",
// among whatever the renderer logs. `what` names the peer in errors.
std::vector<PeerRender> runLadder(const std::vector<std::string>& argv, const fs::path& log, const std::string& what) {
  addProjectModulesToPythonPath();
  ChildProcess ladder(argv, log.string());
  const int status = ladder.wait();
  const std::string text = readAll(log);
  if (status != 0) throw std::runtime_error(fmt::format("{}: the ladder failed:\n{}", what, text));
  static const std::regex row(R"(^([0-9]+),([0-9.]+),(.+\.exr)$)");
  std::vector<PeerRender> renders;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    std::smatch match;
    if (std::regex_match(line, match, row))
      renders.push_back({static_cast<uint32_t>(std::stoul(match[1])), std::stod(match[2]), match[3].str()});
  }
  if (renders.empty()) throw std::runtime_error(fmt::format("{}: the ladder printed no render:\n{}", what, text));
  return renders;
}

void requireMitsuba(const std::string& python) {
  if (!fs::exists(python))
    throw std::runtime_error(fmt::format("--mitsuba: no Mitsuba 3 in {} (run deploy/install-deps.sh --peers, or "
                                         "give --mitsuba-python a python that has mitsuba and drjit)",
                                         python));
}

}  // namespace

std::string defaultMitsubaPython() {
  if (const char* venv = std::getenv("MITSUBA_VENV"); venv && *venv) return std::string(venv) + "/bin/python";
  const char* home = std::getenv("HOME");
  return std::string(home ? home : "") + "/.local/share/portico/mitsuba-venv/bin/python";
}

std::vector<PeerRender> renderWithMitsuba(const std::string& sceneDirectory, const std::string& sppList,
                                          uint32_t threads, const std::string& python, const fs::path& outDirectory) {
  requireMitsuba(python);
  fs::create_directories(outDirectory);
  return runLadder({python, "-m", "portico_mitsuba", sceneDirectory, outDirectory.string(), "--spp", sppList,
                    "--threads", std::to_string(threads)},
                   outDirectory / "mitsuba.log", "--mitsuba");
}

void writePeerView(const std::string& portico, const std::string& store, const std::string& camera, uint32_t width,
                   uint32_t height, const fs::path& viewDirectory) {
  const std::string python = projectPython();
  if (!fs::exists(python))
    throw std::runtime_error(fmt::format("no {} (deploy/install-deps.sh makes the sources' .venv)", python));
  fs::create_directories(viewDirectory);
  std::vector<std::string> argv{python, "-m", "portico_peers", "view", store, viewDirectory.string(), "--portico",
                                portico};
  if (!camera.empty()) argv.insert(argv.end(), {"--camera", camera});
  if (width) argv.insert(argv.end(), {"--width", std::to_string(width)});
  if (height) argv.insert(argv.end(), {"--height", std::to_string(height)});
  addProjectModulesToPythonPath();
  const fs::path log = viewDirectory / "view.log";
  ChildProcess child(argv, log.string());
  if (child.wait() != 0)
    throw std::runtime_error(fmt::format("writing the peers' view of {}:\n{}", store, readAll(log)));
}

std::vector<PeerRender> renderViewWithMitsuba(const fs::path& viewDirectory, const std::string& sppList,
                                              uint32_t threads, const std::string& python) {
  requireMitsuba(python);
  return runLadder({python, "-m", "portico_peers", "mitsuba", viewDirectory.string(), "--spp", sppList, "--threads",
                    std::to_string(threads)},
                   viewDirectory / "mitsuba.log", "--mitsuba");
}

std::vector<PeerRender> renderViewWithLuxcore(const fs::path& viewDirectory, const std::string& sppList,
                                              uint32_t threads, uint64_t photonGi) {
  const std::string python = projectPython();
  return runLadder({python, "-m", "portico_peers", "luxcore", viewDirectory.string(), "--spp", sppList, "--threads",
                    std::to_string(threads), "--photongi", std::to_string(photonGi)},
                   viewDirectory / fmt::format("luxcore-{}.log", photonGi), "--luxcore");
}

}  // namespace portico::cli
