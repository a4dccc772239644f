// Rooms found in a building mesh that carries no topology (`scene import
// --cells rooms`, docs/room-finding.md): a voxel flood fill of free space
// split at narrow openings.
//
//  1. Voxels of `voxelSize` (cubes; grown when the grid would pass
//     `maxVoxels`) over the scene's bounds, padded so that open air
//     surrounds the building; a voxel touched by a triangle is solid.
//  2. The chessboard distance of every free voxel to the nearest solid one
//     (a breadth-first pass over 26 neighbours).
//  3. Cores: free voxels farther than half of `openingWidth` from any solid.
//     A door or window is narrower than that, so it holds no core and the
//     cores on its two sides are separate components; each component larger
//     than `minRoomVolume` is a region. Those touching the grid's boundary
//     are one region, outdoors.
//  4. Every other free voxel joins the region whose core reaches it first
//     (breadth-first over free voxels from all cores at once, ties to the
//     lower voxel index: deterministic); then solid voxels and unreached
//     pockets join the region next to them, so every voxel has a region.
//  5. Each region is cut into few large boxes, the cells (a cell is a box):
//     one grows from each room's deepest air voxel, first over the room's
//     air, then through its walls, floor and ceiling up to the next
//     region's air; rooms before outdoors, so rays hit a room's envelope
//     inside its own cell. Slivers left where regions' fronts meet in an
//     opening are undone and taken by the large boxes. Two boxes meeting on
//     a face are joined by one portal: the whole face they share. (Bounding
//     only the voxel faces with free space beside them let a third of the
//     photons out: a ray grazing a wall crosses faces between voxels its
//     triangles only touch.)
//
// Cells are named "room-R-B" (region R from 1, box B) and "outdoors-B".
// Each room's air (the free voxels its core reached: not the inside of a
// thick wall) is also described (FoundRoom): for lamps and cameras placed
// per room (room_lighting.h) and for checks that need points in a room.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "common/math.h"
#include "common/scene/import/imported_scene.h"
#include "common/scene/store/scene_store.h"

namespace portico {

struct RoomFinderOptions {
  float voxelSize = 0.1f;        // metres (scene units); grown to keep the grid under maxVoxels
  float openingWidth = 1.5f;     // free space narrower than this (doors, windows) separates regions
  float minRoomVolume = 1.0f;    // cubic metres of core below which a component is not a room
  uint64_t maxVoxels = 48ull << 20;
  // The meshes are closed solids with outward faces (an IFC model's
  // elements): a core inside one (a footing block) is no room. Off for
  // meshes in general, whose walls may be single faces.
  bool solidsAreClosed = false;
  // Called with a stage name and its fraction done, a few times a stage.
  std::function<void(const std::string& stage, double fraction)> onProgress;
};

// What a room's air is like: region R (from 1) is "room R".
struct FoundRoom {
  std::string name;              // "room R"
  uint64_t airVoxels = 0;
  double floorArea = 0;          // m^2: air voxels standing on a solid voxel, times a voxel's face
  Bounds3 air;                   // the box of its air voxels
  // Its deepest air voxel (farthest from any solid, the lowest index of
  // those): the middle of its widest part, and the column of air through it.
  Vec3 centre;
  float floor = 0, ceiling = 0;  // bottom and top of that column's air (y)
  // Half the side of the largest square of air, centred on the column, in
  // its top layer of air voxels: how wide a ceiling panel may be.
  float clearHalfWidth = 0;
  // Lowest corners of air voxels spread evenly over the room (every k-th in
  // index order, at most kRoomSamples): points in its air, a voxel apart.
  std::vector<Vec3> samples;
};
constexpr size_t kRoomSamples = 512;

struct FoundRooms {
  std::vector<ImportedCell> cells;       // boxes: the scene's cells
  std::vector<uint32_t> cellRegion;      // per cell: its region, 0 outdoors, 1.. rooms
  std::vector<ImportedPortal> portals;
  uint32_t rooms = 0;                    // regions other than outdoors
  std::vector<FoundRoom> roomAir;        // per room, region 1 first
  // Outdoor air the building shelters (a solid above and below it), wide
  // as a room's core: a room open to the outdoors through a gap wider than
  // an opening (a missing wall), a loggia, a covered balcony. Named
  // "sheltered N"; air box and samples only (of its core voxels).
  std::vector<FoundRoom> shelteredAir;
  float voxelSize = 0;                   // as used
  std::array<uint32_t, 3> voxels{};      // grid size
  // The cell each of the grid's voxels belongs to: for binning triangles.
  std::vector<uint32_t> voxelCell;
  Vec3 origin;                           // the grid's lowest corner
  // The voxel range [first, last] a box [lo, hi] touches along `axis`.
  void touchedVoxels(int axis, float lo, float hi, uint32_t& first, uint32_t& last) const;
  uint32_t voxelIndex(uint32_t x, uint32_t y, uint32_t z) const { return x + voxels[0] * (y + voxels[1] * z); }
  Bounds3 voxelBounds(uint32_t x, uint32_t y, uint32_t z) const;
  float plane(int axis, uint32_t k) const { return origin[axis] + voxelSize * float(k); }
};

// Finds the rooms of `scene` (its objects only). Throws std::runtime_error
// "no rooms found in SOURCE: ...; use --grid N" when no enclosed space is
// found (a single object, open terrain).
FoundRooms findRooms(const ImportedScene& scene, const std::string& source, const RoomFinderOptions& options = {});

// Writes `scene` into `writer` as the cells of `rooms`: portals, lights (an
// axis-aligned quad cut at the boxes it spans, any other whole in the box
// holding its centre, nudged to its emitting side), cameras, then the cells
// one at a time. Materials must already be added in the scene's order.
void writeRoomCells(const ImportedScene& scene, const FoundRooms& rooms, SceneStoreWriter& writer);

}  // namespace portico
