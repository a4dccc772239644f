// `portico scene generate --preset NAME`: furnished multi-floor buildings
// with the statistics of the paper's test scenes (building_presets.h).
//
// A floor is a chain of wings and junctions (the preset's layout). A wing is
// a corridor cell with a row of room cells on each side, each room joined to
// the corridor by a door portal and, through window portals in its outer
// wall, to a facade cell: a strip of open air along the wing, as tall as the
// building, whose top opens to the sky. A junction is a square hall joining
// the corridors of the wings it links (a portal the size of each corridor's
// end); it holds a staircase whose opening in the ceiling is the portal to
// the junction above. Every top-floor cell and every facade opens onto one
// sky cell, which holds an overview camera (ceilings and lamps are hidden
// from the camera: a cut-away of the top floor). Every floor also has two
// named standing cameras: "floorF-room-..." in the doorway of its room with
// the most lights, looking in, and "floorF-corridor" at the end of its first
// corridor, looking along it (floors count from 0, as in cell names).
//
// Rooms are furnished from the furniture library (room_furnisher.h) for a
// triangle budget: the preset's total, with its largest room at the paper's
// maximum, the rest shared by floor area (Regular) or by area times a random
// factor (HandMade). Lights are shared by floor area.
//
// Cells stream to the store one at a time, so peak memory is one cell's
// geometry plus the plan. The same (preset, seed, floors) writes the same bytes.
#pragma once

#include <cstdint>
#include <string>

#include "common/scene/generator/building_presets.h"
#include "common/scene/generator/panel_lighting.h"

namespace portico {

struct GeneratedBuildingStats {
  uint64_t triangles = 0;
  uint32_t cells = 0, portals = 0, lights = 0;
  double seconds = 0;
};

// lighting: the ceiling panels' flux and colour (panel_lighting.h); a
// problem with it is a std::invalid_argument naming the option.
GeneratedBuildingStats generateBuilding(const BuildingPreset& preset, uint64_t seed, const std::string& storeDirectory,
                                        const PanelLighting& lighting = {});

}  // namespace portico
