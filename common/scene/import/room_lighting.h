// Lamps and cameras for rooms found in a building that brings none of its
// own: an IFC model without usable IfcSpace, whose rooms the room finder
// finds (docs/importing-buildings.md). Each found room gets what the IFC
// converter gives each space (python/portico_ifc/lights_cameras.py): a
// ceiling panel of 4 % of its floor area, emitting 250 lm per m^2 of floor
// downwards in the generated buildings' panel colour, and a camera at eye
// height looking across the room. Both are placed from the room's air
// (FoundRoom): over its deepest point, where it is widest, under the
// ceiling of that column, so they lie in the room and not in a wall.
#pragma once

#include "common/scene/import/imported_scene.h"
#include "common/scene/import/room_cells.h"

namespace portico {

// Adds one ceiling panel per room to `scene`: an emissive quad object (its
// own material, "lamp room N") and its light.
void addRoomLamps(const FoundRooms& rooms, ImportedScene& scene);

// Adds one camera per room, named "room N", in front of the scene's own
// cameras (so room 1's is the default) unless `keepDefault`, when they go
// after the first.
void addRoomCameras(const FoundRooms& rooms, bool keepDefault, ImportedScene& scene);

}  // namespace portico
