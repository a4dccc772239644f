// Reads a building.json (format: docs/building-json.md) into plain records,
// checking everything that can be checked without the meshes: types, finite
// numbers, albedo range, cell names, portal polygons, cameras. Mesh-dependent
// checks (files exist, triangles inside their cell, emitters are quads,
// camera inside a cell) are the importer's.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "common/math.h"
#include "common/scene/store/scene_types.h"

namespace portico {

struct BuildingObject {
  size_t index = 0;          // position in "objects"
  std::string name;          // "name", else the mesh file's stem
  std::string meshPath;      // resolved against the json's directory
  std::string cell;          // "cell"; empty when the file has no "cells"
  Vec3 albedo;
  Vec3 emission;             // zero when null or absent
  // "objects[3] ('light')": how messages name the object.
  std::string label() const;
};

struct BuildingCell {
  std::string name;
  Bounds3 bounds;
};

struct BuildingPortal {
  size_t index = 0;
  std::string cellA, cellB;
  std::vector<Vec3> polygon;
};

struct BuildingCamera {
  std::string name;          // "name" of an entry of "cameras"; "camera" for the single one
  Camera camera;             // cell not set yet
};

struct BuildingDescription {
  std::string path;          // the json file, as given
  std::string name;          // "name", or the file's stem
  std::vector<BuildingObject> objects;
  std::optional<std::vector<BuildingCell>> cells;   // absent: one cell around everything
  std::vector<BuildingPortal> portals;
  std::vector<BuildingCamera> cameras;              // at least one
};

// Throws std::runtime_error, one line starting with the path and naming the
// object, cell, portal or camera at fault.
BuildingDescription readBuildingJson(const std::string& path);

}  // namespace portico
