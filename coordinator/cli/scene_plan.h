// `portico scene plan`: top-down floor plans of a scene store, so people can
// see the layout. One panel per floor (floors as in common/scene/store/
// floor_levels.h), panels in a grid; x to the right, z downwards (the view
// from above, +y towards the viewer).
//
//  * Cells: their x-z footprint filled in a colour hashed from the id, with
//    a darker outline; larger cells first, so small ones stay visible. An
//    empty cell covering half the building or more (a sky, the outdoors)
//    is left out.
//  * Vertical portals (doors, windows) are thick segments where they stand:
//    red between two drawn cells, blue to a cell left out (a window).
//  * Horizontal portals (stairwells, floor openings) are hatched purple
//    rectangles on the floors of both their cells; those to a cell left out
//    (a cut-away to the sky) are not drawn.
//  * Lights: small yellow squares at their centres.
#pragma once

#include <vector>

#include "common/scene/store/scene_store.h"
#include "coordinator/cli/png_canvas.h"

namespace portico::cli {

// Per cell id: whether a plan draws it (every cell but an empty one
// covering half the building's footprint or more: a sky, the outdoors).
std::vector<bool> cellsToDraw(const SceneStore& store);

// The plans of every floor (floor < 0) or of one. panelSize: pixels along a
// panel's longer side, reduced when the picture would be too big. Throws
// std::runtime_error naming the store when `floor` does not exist.
Canvas drawFloorPlans(const SceneStore& store, int floor, int panelSize);

}  // namespace portico::cli
