#include "coordinator/cli/bench/radiance_runner.h"

#include <fmt/format.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "common/util/child_process.h"

namespace portico::cli {

namespace {

namespace fs = std::filesystem;

// One word for sh: in single quotes, a quote in it closed, escaped, reopened.
std::string shellWord(const std::string& word) {
  std::string quoted = "'";
  for (char c : word) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

std::string pyradianceIn(const fs::path& venvLib) {
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(venvLib, error)) {
    const fs::path package = entry.path() / "site-packages" / "pyradiance";
    if (entry.path().filename().string().rfind("python3", 0) == 0 && ::access((package / "bin" / "rtrace").c_str(), X_OK) == 0)
      return package.string();
  }
  return "";
}

}  // namespace

std::optional<RadianceInstall> findRadiance() {
  if (const std::string package = pyradianceIn(fs::path(PORTICO_SOURCE_DIR) / ".venv" / "lib"); !package.empty())
    return RadianceInstall{package + "/bin", package + "/lib"};
  const char* path = std::getenv("PATH");
  std::stringstream folders(path ? path : "");
  for (std::string folder; std::getline(folders, folder, ':');)
    if (!folder.empty() && ::access((fs::path(folder) / "rtrace").c_str(), X_OK) == 0) {
      const char* rayPath = std::getenv("RAYPATH");
      return RadianceInstall{folder, rayPath ? rayPath : ""};
    }
  return std::nullopt;
}

void runRadiance(const RadianceInstall& radiance, const std::vector<std::string>& argv, const std::string& input,
                 const std::string& output, const std::string& log) {
  std::string script = fmt::format("PATH={}:\"$PATH\" RAYPATH=.:{}${{RAYPATH:+:$RAYPATH}} exec", shellWord(radiance.bin),
                                   shellWord(radiance.lib));
  script += " " + shellWord((fs::path(radiance.bin) / argv.front()).string());
  for (size_t i = 1; i < argv.size(); ++i) script += " " + shellWord(argv[i]);
  if (!input.empty()) script += " < " + shellWord(input);
  script += " > " + shellWord(output);
  ChildProcess child({"/bin/sh", "-c", script}, log);
  if (child.wait() != 0) {
    std::ifstream in(log);
    throw std::runtime_error(fmt::format("{} failed:\n{}", argv.front(), std::string(std::istreambuf_iterator<char>(in), {})));
  }
}

std::vector<Vec3> readRtraceIrradiance(const std::string& path) {
  std::ifstream in(path);
  std::vector<Vec3> values;
  for (std::string line; std::getline(in, line);) {
    std::istringstream words(line);
    Vec3 v;
    if (words >> v.x >> v.y >> v.z) values.push_back(v);
  }
  return values;
}

}  // namespace portico::cli
