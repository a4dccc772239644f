// `portico scene import model.ifc STORE`: converts the model
// (ifc_conversion.h) and stores it. A model whose IfcSpaces give no cells
// (none, or too thin) comes out of the converter as geometry only, marked
// in conversion.json ("find_rooms"); its rooms are then found in that
// geometry (room_cells.h), each given a camera and, where the model has no
// light fixtures, a ceiling panel (room_lighting.h), and the rooms' air is
// recorded in the store's conversion.json ("found_rooms", for
// python -m portico_ifc.watertight). docs/importing-buildings.md.
#pragma once

#include <string>

#include "common/scene/import/building_importer.h"
#include "coordinator/cli/ifc_conversion.h"

namespace portico::cli {

// `options` as for any import (its room search's progress callbacks are
// used); throws std::runtime_error of one line, leaving no store behind.
ImportSummary importIfcModel(const std::string& ifc, const std::string& store, const ImportOptions& options,
                             const IfcOptions& ifcOptions);

}  // namespace portico::cli
