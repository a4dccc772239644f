// The project's Python modules (python/ in the sources: the IFC converter,
// the Mitsuba ladder), which `portico` runs in an interpreter of the user's
// choice (a virtual environment that holds their dependencies).
#pragma once

namespace portico::cli {

// Puts the sources' python/ folder first on this process's PYTHONPATH, so
// that the children it starts find the modules.
void addProjectModulesToPythonPath();

}  // namespace portico::cli
