#include "coordinator/cli/ifc_conversion.h"

#include <fmt/format.h>
#include <spawn.h>
#include <sys/wait.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <vector>

#include "common/util/project_python.h"
#include "coordinator/cli/python_modules.h"

extern char** environ;

namespace portico::cli {

namespace {

int runProcess(const std::vector<std::string>& arguments) {
  std::vector<char*> argv;
  for (const std::string& a : arguments) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0) return -1;
  int status = 0;
  if (waitpid(pid, &status, 0) < 0 || !WIFEXITED(status)) return -1;
  return WEXITSTATUS(status);
}

}  // namespace

bool isIfcFile(const std::string& path) {
  std::string extension = std::filesystem::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) { return std::tolower(c); });
  return extension == ".ifc";
}

std::string convertIfc(const std::string& ifc, const std::string& outDirectory, const IfcOptions& options) {
  if (!std::filesystem::is_regular_file(ifc)) throw std::runtime_error(fmt::format("{}: does not exist", ifc));
  const std::string python = projectPython();   // IfcOpenShell is not packaged by Debian
  if (!std::filesystem::exists(python))
    throw std::runtime_error(fmt::format("{}: reading IFC needs IfcOpenShell in {} (run deploy/install-deps.sh, or set "
                                         "PORTICO_PYTHON to a python3 that has ifcopenshell)",
                                         ifc, python));
  addProjectModulesToPythonPath();
  std::vector<std::string> arguments{python,    "-m",         "portico_ifc",   ifc,
                                     outDirectory, "--lights", options.lights, "--outdoors",
                                     options.outdoors};
  if (!options.glazing) arguments.push_back("--no-glazing");
  if (options.findRooms) arguments.insert(arguments.end(), {"--cells", "rooms"});
  const int status = runProcess(arguments);
  if (status != 0)
    throw std::runtime_error(fmt::format("{}: the IFC converter failed (exit status {}; its message is above)", ifc, status));
  return outDirectory + "/building.json";
}

}  // namespace portico::cli
