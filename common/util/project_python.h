// The Python interpreter that runs the sources' own modules (python/): the
// virtual environment deploy/install-deps.sh makes beside the sources, which
// holds their PyPI dependencies (IfcOpenShell, flip-evaluator, pyluxcore,
// ...), unless $PORTICO_PYTHON names another. A target using it defines
// PORTICO_SOURCE_DIR.
#pragma once

#include <cstdlib>
#include <string>

namespace portico {

inline std::string projectPython() {
  if (const char* python = std::getenv("PORTICO_PYTHON"); python && *python) return python;
  return std::string(PORTICO_SOURCE_DIR) + "/.venv/bin/python3";
}

}  // namespace portico
