// The catalogue's SQLite schema, shared by SceneStore (reader) and
// SceneStoreWriter. Private to common/scene/store: nothing else should depend on
// table layouts; it goes through SceneStore.
#pragma once

#include <cstdint>
#include <string_view>

namespace portico::scene_schema {

// PRAGMA user_version of scene.db. A reader refuses any other value: bump it
// (and teach SceneStore::open to read the old one, or say how to regenerate)
// whenever a table changes.
//   1: first version.
//   2: materials.hidden_from_camera (cut-away surfaces). Version 1 is still
//      read, as if every material had hidden_from_camera = 0.
//   3: lights.shape ('parallelogram' or 'triangle'). Versions 1 and 2 are
//      still read, every light a parallelogram.
//   4: table cameras (named; id 0 the default) replaces table camera.
//      Versions 1 to 3 are still read, their one camera named "default".
//   5: table material_textures (a material's albedo texture, a file under
//      textures/). Versions 1 to 4 are still read, with no textures.
//   6: materials.transmittance_r/g/b and ior (thin glass). Versions 1 to 5
//      are still read, without glass.
//   7: table site (where the building stands: latitude, longitude, north
//      azimuth; no row when unknown). Versions 1 to 6 are still read,
//      without a site.
//   8: shape 'point' (a point luminaire) in lights; tables
//      light_distributions (a photometric file's candela grid) and
//      point_lights (which distribution each point luminaire has).
//      Versions 1 to 7 are still read, without point luminaires.
//   9: point_lights.opening_width/length/height (a luminaire's luminous
//      opening, metres, LM-63 signs: what cameras see). Version 8 is still
//      read, every opening 0 0 0 (a point no camera sees).
constexpr int kVersion = 9;
constexpr int kOldestReadableVersion = 1;

constexpr std::string_view kDatabaseFile = "scene.db";
constexpr std::string_view kCellDirectory = "cells";
constexpr std::string_view kTextureDirectory = "textures";

// Portal polygons are a BLOB of little-endian float32, xyz per vertex, in
// order around the polygon: exact (no decimal round trip) and compact. All
// other coordinates are REAL columns, which hold a float exactly. Camera 0
// is the store's default camera. A light distribution's angles (degrees)
// and candela values (horizontal-major, CandelaGrid) are BLOBs of
// little-endian float64.
constexpr std::string_view kCreateTables = R"sql(
CREATE TABLE meta(
  key   TEXT PRIMARY KEY,
  value TEXT NOT NULL);
CREATE TABLE cells(
  id INTEGER PRIMARY KEY,
  name TEXT NOT NULL,
  min_x REAL NOT NULL, min_y REAL NOT NULL, min_z REAL NOT NULL,
  max_x REAL NOT NULL, max_y REAL NOT NULL, max_z REAL NOT NULL,
  triangle_count INTEGER NOT NULL,
  byte_count INTEGER NOT NULL,
  file TEXT NOT NULL);
CREATE TABLE portals(
  id INTEGER PRIMARY KEY,
  cell_a INTEGER NOT NULL REFERENCES cells(id),
  cell_b INTEGER NOT NULL REFERENCES cells(id),
  polygon BLOB NOT NULL);
CREATE INDEX portals_by_cell_a ON portals(cell_a);
CREATE INDEX portals_by_cell_b ON portals(cell_b);
CREATE TABLE materials(
  id INTEGER PRIMARY KEY,
  name TEXT NOT NULL,
  albedo_r REAL NOT NULL, albedo_g REAL NOT NULL, albedo_b REAL NOT NULL,
  emission_r REAL NOT NULL, emission_g REAL NOT NULL, emission_b REAL NOT NULL,
  hidden_from_camera INTEGER NOT NULL DEFAULT 0 CHECK (hidden_from_camera IN (0, 1)),
  transmittance_r REAL NOT NULL DEFAULT 0, transmittance_g REAL NOT NULL DEFAULT 0,
  transmittance_b REAL NOT NULL DEFAULT 0,
  ior REAL NOT NULL DEFAULT 1.5);
CREATE TABLE material_textures(
  material INTEGER PRIMARY KEY REFERENCES materials(id),
  albedo_texture TEXT NOT NULL);
CREATE TABLE lights(
  id INTEGER PRIMARY KEY,
  cell INTEGER NOT NULL REFERENCES cells(id),
  corner_x REAL NOT NULL, corner_y REAL NOT NULL, corner_z REAL NOT NULL,
  edge1_x REAL NOT NULL, edge1_y REAL NOT NULL, edge1_z REAL NOT NULL,
  edge2_x REAL NOT NULL, edge2_y REAL NOT NULL, edge2_z REAL NOT NULL,
  radiance_r REAL NOT NULL, radiance_g REAL NOT NULL, radiance_b REAL NOT NULL,
  shape TEXT NOT NULL DEFAULT 'parallelogram' CHECK (shape IN ('parallelogram', 'triangle', 'point')));
CREATE TABLE light_distributions(
  id INTEGER PRIMARY KEY,
  name TEXT NOT NULL,
  vertical BLOB NOT NULL,
  horizontal BLOB NOT NULL,
  candela BLOB NOT NULL);
CREATE TABLE point_lights(
  light INTEGER PRIMARY KEY REFERENCES lights(id),
  distribution INTEGER NOT NULL REFERENCES light_distributions(id),
  opening_width REAL NOT NULL DEFAULT 0,
  opening_length REAL NOT NULL DEFAULT 0,
  opening_height REAL NOT NULL DEFAULT 0);
CREATE TABLE cameras(
  id INTEGER PRIMARY KEY,
  name TEXT NOT NULL UNIQUE,
  origin_x REAL NOT NULL, origin_y REAL NOT NULL, origin_z REAL NOT NULL,
  target_x REAL NOT NULL, target_y REAL NOT NULL, target_z REAL NOT NULL,
  up_x REAL NOT NULL, up_y REAL NOT NULL, up_z REAL NOT NULL,
  fov_y_deg REAL NOT NULL,
  width INTEGER NOT NULL,
  height INTEGER NOT NULL,
  cell INTEGER NOT NULL REFERENCES cells(id));
CREATE TABLE site(
  id INTEGER PRIMARY KEY CHECK (id = 0),
  latitude REAL NOT NULL,
  longitude REAL NOT NULL,
  north_azimuth REAL NOT NULL);
)sql";

}  // namespace portico::scene_schema
