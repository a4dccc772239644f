#include "coordinator/cli/bench/mitsuba_ladder.h"

#include <fmt/format.h>

#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>

#include "common/util/child_process.h"
#include "coordinator/cli/python_modules.h"

namespace portico::cli {

namespace fs = std::filesystem;

namespace {

// Dr.Jit's LLVM back end loads libLLVM at run time and does not look for
// Debian's versioned name; libllvm19 (install-deps.sh --mitsuba) installs it here.
constexpr const char* kDebianLibLlvm = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1";

}  // namespace

std::string defaultMitsubaPython() {
  if (const char* venv = std::getenv("MITSUBA_VENV"); venv && *venv) return std::string(venv) + "/bin/python";
  const char* home = std::getenv("HOME");
  return std::string(home ? home : "") + "/.local/share/portico/mitsuba-venv/bin/python";
}

std::vector<MitsubaRender> renderWithMitsuba(const std::string& sceneDirectory, const std::string& sppList,
                                             uint32_t threads, const std::string& python,
                                             const fs::path& outDirectory) {
  if (!fs::exists(python))
    throw std::runtime_error(fmt::format("--mitsuba: no Mitsuba 3 in {} (run deploy/install-deps.sh --mitsuba, or "
                                         "give --mitsuba-python a python that has mitsuba and drjit)",
                                         python));
  addProjectModulesToPythonPath();
  const char* libLlvm = std::getenv("DRJIT_LIBLLVM_PATH");
  if ((!libLlvm || !*libLlvm) && fs::exists(kDebianLibLlvm)) setenv("DRJIT_LIBLLVM_PATH", kDebianLibLlvm, 1);

  fs::create_directories(outDirectory);
  const fs::path log = outDirectory / "mitsuba.log";
  ChildProcess ladder({python, "-m", "portico_mitsuba", sceneDirectory, outDirectory.string(), "--spp", sppList,
                       "--threads", std::to_string(threads)},
                      log.string());
  const int status = ladder.wait();
  std::ifstream in(log);
  const std::string text(std::istreambuf_iterator<char>(in), {});
  if (status != 0) throw std::runtime_error(fmt::format("--mitsuba: Mitsuba's ladder failed:\n{}", text));

  // Its rows, "spp,seconds,image", among whatever Mitsuba logs.
  static const std::regex row(R"(^([0-9]+),([0-9.]+),(.+\.exr)$)");
  std::vector<MitsubaRender> renders;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    std::smatch match;
    if (std::regex_match(line, match, row))
      renders.push_back({static_cast<uint32_t>(std::stoul(match[1])), std::stod(match[2]), match[3].str()});
  }
  if (renders.empty()) throw std::runtime_error(fmt::format("--mitsuba: Mitsuba's ladder printed no render:\n{}", text));
  return renders;
}

}  // namespace portico::cli
