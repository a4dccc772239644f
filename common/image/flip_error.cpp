#include "common/image/flip_error.h"

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>

#include "common/util/child_process.h"
#include "common/util/project_python.h"

namespace portico {

namespace {

namespace fs = std::filesystem;

std::string lastLine(const std::string& text) {
  const size_t end = text.find_last_not_of('\n');
  if (end == std::string::npos) return "";
  const size_t start = text.rfind('\n', end);
  return text.substr(start == std::string::npos ? 0 : start + 1, end - (start == std::string::npos ? 0 : start + 1) + 1);
}

}  // namespace

FlipResult flipError(const std::string& image, const std::string& reference) {
  const std::string python = projectPython();
  if (::access(python.c_str(), X_OK) != 0)
    return {std::nullopt, "no " + python + " (deploy/install-deps.sh makes the .venv)"};
  const fs::path log = fs::temp_directory_path() / ("portico-flip-" + std::to_string(::getpid()) + ".log");
  int status = 0;
  {
    // PYTHONPATH only for the child: the sources' python/ holds the module.
    const std::string modules = std::string(PORTICO_SOURCE_DIR) + "/python";
    ChildProcess flip({"/usr/bin/env", "PYTHONPATH=" + modules, python, "-m", "portico_quality.flip", image, reference},
                      log.string());
    status = flip.wait();
  }
  std::ifstream in(log);
  const std::string text(std::istreambuf_iterator<char>(in), {});
  fs::remove(log);
  static const std::regex line(R"(^flip ([0-9.]+)$)");
  std::smatch match;
  const std::string last = lastLine(text);
  if (status == 0 && std::regex_match(last, match, line)) return {std::stod(match[1]), ""};
  return {std::nullopt, last.empty() ? "FLIP exited with status " + std::to_string(status) : last};
}

}  // namespace portico
