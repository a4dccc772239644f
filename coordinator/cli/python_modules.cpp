#include "coordinator/cli/python_modules.h"

#include <cstdlib>
#include <string>

namespace portico::cli {

void addProjectModulesToPythonPath() {
  const std::string modules = std::string(PORTICO_SOURCE_DIR) + "/python";
  const char* previous = std::getenv("PYTHONPATH");
  setenv("PYTHONPATH", previous && *previous ? (modules + ":" + previous).c_str() : modules.c_str(), 1);
}

}  // namespace portico::cli
