// Reads a building.json (format: docs/building-json.md) into plain records,
// checking everything that can be checked without the meshes: types, finite
// numbers, albedo range, cell names, portal polygons, cameras. Mesh-dependent
// checks (files exist, triangles inside their cell, camera inside a cell)
// are the importer's.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/math.h"
#include "common/scene/store/scene_types.h"
#include "common/scene/store/site_location.h"

namespace portico {

// A lamp's output in photometric terms: "lumens" with "colour_temperature"
// (kelvin) or "colour" ([r, g, b], any scale); neither: 4000 K.
struct LampOutput {
  double lumens = 0;
  Vec3 colour;               // linear Rec. 709, luminance Y = 1
};

struct BuildingObject {
  size_t index = 0;          // position in "objects"
  std::string name;          // "name", else the mesh file's stem
  std::string meshPath;      // resolved against the json's directory
  std::string cell;          // "cell"; empty when the file has no "cells"
  // Absent: every part of the mesh file takes the file's own material.
  std::optional<Vec3> albedo;
  std::optional<Vec3> emission;   // absent when null or not given
  // "lumens" instead of "emission": spread uniformly over every triangle of
  // the mesh file (the importer turns it into a radiance by their area).
  std::optional<LampOutput> lumens;
  // "glass": thin glass of this tint and index, instead of albedo.
  struct Glass {
    Vec3 transmittance;
    float ior = 1.5f;
  };
  std::optional<Glass> glass;
  // "objects[3] ('light')": how messages name the object.
  std::string label() const;
};

// An entry of "lights": a quad (corner + s*edge1 + t*edge2) or a triangle
// (corner, corner + edge1, corner + edge2), emitting on the side of
// cross(edge1, edge2).
struct BuildingLight {
  size_t index = 0;          // position in "lights"
  std::string name;          // "name", else "light-<index>"
  std::string cell;          // "cell"; empty when the file has no "cells"
  LightShape shape = LightShape::Parallelogram;
  Vec3 corner, edge1, edge2;
  Vec3 radiance;             // given, or from "lumens" and the shape's area
  // "ies": a point luminaire (shape Point; docs/photometric-lights.md):
  // corner is its "position", edge1 its "aim" (the nadir), edge2 its "c0";
  // radiance the RGB intensity per candela (W/sr per cd).
  std::shared_ptr<const LuminousIntensity> intensity;
  LuminousOpening opening;   // the file's, or "opening" [width, length, height]
  std::string iesPath;       // resolved against the json's directory
  // "lights[2] ('desk lamp')": how messages name the light.
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
  std::string name;          // "name" of an entry of "cameras"; "default" for the single one
  Camera camera;             // named as above; cell not set yet
};

struct BuildingDescription {
  std::string path;          // the json file, as given
  std::string name;          // "name", or the file's stem
  std::vector<BuildingObject> objects;
  std::vector<BuildingLight> lights;
  std::optional<std::vector<BuildingCell>> cells;   // absent: one cell around everything
  std::vector<BuildingPortal> portals;
  std::vector<BuildingCamera> cameras;              // at least one
  std::optional<SiteLocation> site;                 // "site": where the building stands
};

// Throws std::runtime_error, one line starting with the path and naming the
// object, cell, portal or camera at fault.
BuildingDescription readBuildingJson(const std::string& path);

}  // namespace portico
