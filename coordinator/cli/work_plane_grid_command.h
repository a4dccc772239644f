// The work-plane grid on the command line: its options (--grid-height,
// --grid-spacing, --grid-inset, --grid-rooms, --grid-floors, --grid-cells),
// shared by `portico analyze --grid auto` and `portico scene grid`, which
// writes a store's grid as a .pts file without measuring it.
#pragma once

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

#include "common/analysis/work_plane_grid.h"

namespace portico::cli {

// Returns the options added (so `analyze` can make them need --grid auto).
std::vector<CLI::Option*> addWorkPlaneGridOptions(CLI::App& command, WorkPlaneGridOptions& options);

// Places the grid, writes it to `output` (.pts) and prints per floor the
// rooms and points (a line per room with `verbose`). Returns 0, or 1 when
// no room got a point.
int runSceneGrid(const std::string& store, const std::string& output, const WorkPlaneGridOptions& options,
                 bool verbose);

}  // namespace portico::cli
