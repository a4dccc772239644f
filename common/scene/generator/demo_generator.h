// The "demo" scene: a small furnished floor for trying portico and for tests.
//
// One floor, shown as a cut-away: a corridor along x (14 m x 2 m) with three
// rooms on each side (4-5 m wide, 4 m deep, 2.8 m high), each joined to the
// corridor by a 0.9 m x 2.1 m door portal. Each room and the corridor has a
// ceiling at 2.8 m and flush ceiling lights, both of materials hidden from
// a camera above them (they still light and reflect; a camera in the room
// sees them); each cell's box reaches 0.1 m
// above its ceiling, where its top face is a portal to the "sky" cell that
// holds the camera, looking down at about 58 degrees so every room shows in
// a 480x320 image. Five rooms and the corridor (twice) have a warm area
// light; "dark-room" has none and is lit only through its door, which faces
// a corridor light: the case photon mapping is for.
//
// Cameras: "overview" (the default, in the sky), one per room named as the
// room, standing in its doorway and looking in, and "corridor", at the
// corridor's west end looking along it.
//
// Cells: 0 corridor, 1-3 north rooms ("room-1".."room-3", west to east),
// 4 "room-4", 5 "dark-room", 6 "room-5" (south, west to east), 7 "sky".
// The layout is fixed; the seed varies the door positions, light sizes,
// wall colours and furniture. The same seed writes the same bytes.
#pragma once

#include <cstdint>
#include <string>

#include "common/scene/generator/panel_lighting.h"

namespace portico {

constexpr uint32_t kDemoCorridorCell = 0;
constexpr uint32_t kDemoDarkRoomCell = 5;
constexpr uint32_t kDemoSkyCell = 7;
constexpr uint32_t kDemoCellCount = 8;

// Writes the demo building as a scene store at storeDirectory (replacing an
// earlier store there). Throws std::runtime_error on failure.
// lighting: the ceiling panels' flux and colour (panel_lighting.h).
void generateDemoBuilding(const std::string& storeDirectory, uint64_t seed, const PanelLighting& lighting = {});

}  // namespace portico
