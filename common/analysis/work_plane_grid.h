// `--grid auto`: sensors on a horizontal work plane in every room of a
// scene store, facing up (+y, the store's up axis), as lighting designers
// lay them out for EN 12464-1 or LEED.
//
// Per chosen cell:
//  * its floor is the largest area of up-facing level triangles in the
//    lower half of the cell (desk and bed tops are smaller than the floor);
//  * candidate points form a square lattice `spacing` apart, centred on the
//    floor's extent, at `height` above the floor;
//  * a point is kept when
//     - the floor lies under it and under every point of a circle of radius
//       `inset` round it (so it keeps `inset` from the floor's edges: walls
//       of a generated room, stair openings, the cell's end for an imported
//       one),
//     - it keeps `inset` from the walls: the cell's triangles cut 1.5 m
//       above the floor, as `portico scene plan` draws them (tall
//       cupboards and shelves count as walls),
//     - nothing of the cell crosses its vertical from 2 cm below the work
//       plane to kHeadroom above it: it is not inside or under furniture
//       (cupboards, shelves, counters, monitors, chair backs). Furniture
//       lower than the work plane (desks, tables, beds) keeps its points:
//       they measure the light arriving over it, as on a Radiance grid,
//     - it lies under a ceiling or roof of the cell (some triangle above
//       it), or under a portal into an indoor cell above (a gallery, the
//       voxel cell above): a point over the low end of a pitched roof lies
//       outside the building though inside the cell's box;
//  * a cell whose floor is less than half covered by its own triangles (a
//    ceiling, a roof) is outdoors, no room, and gets no points; a room
//    partly open to a gallery above keeps the points under the opening.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/analysis/sensor.h"
#include "common/scene/store/scene_store.h"

namespace portico {

constexpr float kHeadroom = 1.0f;   // metres above the work plane that must be free

struct WorkPlaneGridOptions {
  float height = 0.8f;    // metres above the room's floor
  float spacing = 0.5f;   // metres between neighbouring points
  float inset = 0.5f;     // metres kept from walls and the floor's edges
  // Which cells: each list given narrows the choice; all empty = every cell.
  std::vector<std::string> roomNames;   // shell patterns (fnmatch) on cell names
  std::vector<uint32_t> floors;         // floors as findFloorLevels numbers them
  std::vector<uint32_t> cells;          // cell ids
};

// One chosen cell with a floor.
struct WorkPlaneRoom {
  uint32_t cell = 0;
  std::string name;
  uint32_t floor = 0;        // findFloorLevels' floor of the cell
  float floorHeight = 0;     // y of the floor the plane stands on
  double floorArea = 0;      // m^2 of that floor (its triangles' area)
  uint32_t sensors = 0;      // points kept
};

struct WorkPlaneGrid {
  std::vector<Sensor> sensors;        // by cell id, then rows of increasing z, then x
  std::vector<WorkPlaneRoom> rooms;   // the chosen rooms that got a point, by cell id
};

// The floor of cell `cell` as the grid finds it (above); nullopt when the
// cell has no up-facing level triangle in its lower half. Throws the
// store's errors reading the cell file.
struct RoomFloor {
  float height = 0;   // y
  double area = 0;    // m^2 of its triangles
};
std::optional<RoomFloor> findRoomFloor(const SceneStore& store, uint32_t cell);

// Throws std::runtime_error naming the option when an option is out of
// range (height, spacing or inset not finite and positive) or a chosen
// cell or floor does not exist, and the store's errors reading a cell file.
WorkPlaneGrid placeWorkPlaneGrid(const SceneStore& store, const WorkPlaneGridOptions& options);

}  // namespace portico
