// Imports a building into a scene store: `portico scene import`.
//
// Inputs are either one building.json (docs/building-json.md: objects with a
// mesh file, cell, albedo (or the file's materials) and emission; lights;
// cells; portals; camera) or one or
// more mesh files (OBJ, PLY, glTF/GLB, anything Assimp reads), which become
// one cell around everything, materials from the files' colours and a
// default camera. Emissive objects become AreaLights (and stay geometry, so
// rays can hit them): a parallelogram of two triangles one quad light, any
// other shape one triangle light per triangle. A building.json may also
// list lights directly ("lights": quads and triangles).
//
// With ImportOptions::gridResolution = RG > 0 the scene is cut into RG^3
// voxel cells instead of its own cells (voxel_cells.h): the same building can
// be rendered with topological or uniform cells. With findRooms its rooms
// are found in the geometry (room_cells.h).
//
// Everything is read and checked before the store is created, so a failed
// import leaves no directory behind: every error is a std::runtime_error of
// one line naming the file and the object at fault. Degenerate (zero-area)
// triangles are not errors: they are dropped and counted.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "common/scene/import/room_cells.h"

namespace portico {

struct ImportOptions {
  // 0: the building.json's cells (or one cell). RG in [1, 256]: RG^3 voxels.
  uint32_t gridResolution = 0;
  // The entry of the building.json's "cameras" that becomes the store's
  // default camera, by "name"; empty: the first. Every entry is stored.
  std::string camera;
  // Called after each object's mesh file is read (objects read, objects in
  // all): reading tens of thousands of mesh files takes a minute.
  std::function<void(size_t read, size_t objects)> onMeshRead;
  // Find rooms and portals in the geometry instead (room_cells.h, `--cells
  // rooms`): for meshes that carry no topology. Not with gridResolution.
  bool findRooms = false;
  RoomFinderOptions rooms;
  // After a room search: rooms found, cells (boxes) and portals.
  std::function<void(uint32_t rooms, size_t cells, size_t portals)> onRoomsFound;
  // With findRooms, for a building that brings no lamps or cameras of its
  // own (an IFC model without IfcSpace): a ceiling panel and a camera per
  // found room (room_lighting.h).
  bool lampPerFoundRoom = false;
  bool cameraPerFoundRoom = false;
};

// The largest gridResolution accepted (16.7 million cells).
constexpr uint32_t kMaxImportGridResolution = 256;

// What an import did besides writing the store; also in the store's meta
// ("degenerate_triangles_dropped").
struct ImportSummary {
  uint64_t triangles = 0;                    // of the input, as kept (before any grid cutting)
  uint64_t degenerateTrianglesDropped = 0;   // zero-area triangles of the meshes, left out
  uint64_t lights = 0;                       // as imported (before any grid cutting)
  // One line each, for the user: the scene has no lights (it would render
  // black, so `portico render` refuses it), saying how to add one.
  std::vector<std::string> warnings;
  // With findRooms: each room's air (room_cells.h), the cells and portals.
  std::vector<FoundRoom> rooms;
  std::vector<FoundRoom> shelteredAir;       // FoundRooms::shelteredAir
  size_t roomCells = 0, roomPortals = 0;
  float roomVoxelSize = 0;                   // as used (grown on very large buildings)
};

ImportSummary importBuilding(const std::vector<std::string>& inputs, const std::string& storeDirectory,
                             const ImportOptions& options = {});

}  // namespace portico
