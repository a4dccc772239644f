// `portico scene import model.ifc STORE`: the IFC model goes through the
// IfcOpenShell converter (python/portico_ifc, docs/importing-buildings.md)
// into a building.json and its OBJ files, which the usual importer stores.
#pragma once

#include <string>

namespace portico::cli {

bool isIfcFile(const std::string& path);

// How the converter reads a model (docs/importing-buildings.md).
struct IfcOptions {
  std::string lights = "auto";   // auto, fixtures, panels or none
  bool glazing = true;           // windows' glass as thin panes; false: windows left out, holes open
  std::string outdoors = "open"; // open: outdoor cells for daylight; closed: black sky and grey ground boxes
  bool findRooms = false;        // find rooms in the geometry even where the model has usable IfcSpace
  std::string keepConversion;    // non-empty: keep the converter's files (and the rooms found) in this directory
};

// Runs the converter on `ifc`, writing building.json, meshes/ and
// conversion.json into `outDirectory`; returns the building.json's path.
// Throws std::runtime_error, one line naming the file, when the converter
// cannot run or fails.
std::string convertIfc(const std::string& ifc, const std::string& outDirectory, const IfcOptions& options);

}  // namespace portico::cli
