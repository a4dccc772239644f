// The generated buildings of `portico scene generate --preset NAME`, sized
// to the paper's test scenes (Fradin & Meneveaux 2006, Tables 1 and 2): the
// totals they must reproduce and the plan that gets there.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/scene/generator/room_furnisher.h"

namespace portico {

// The paper's photon passes shoot 50 000 photons per light (Table 1: 7.75 M
// into the octagon's 155 lights, 1.2 M into the l-shape's 24), and 20 000 in
// its "few photons" runs (Fig. 8, top).
constexpr uint64_t kPaperPhotonsPerLight = 50000, kPaperFewPhotonsPerLight = 20000;

// How the wings of a floor join: each wing is a corridor with rooms on both
// sides; junctions are square halls holding the stairs.
enum class BuildingLayout : uint8_t {
  Bar,      // wing, junction, wing in a straight line (soda-hall)
  LShape,   // wing, junction, wing turned 90 degrees (l-shape)
  ZShape,   // wing, junction, wing, junction, wing (z-building)
  Ring,     // four wings and four corner junctions round a courtyard (octagon, tower)
};

struct BuildingPreset {
  std::string name;
  BuildingLayout layout = BuildingLayout::Bar;
  furniture::Style style = furniture::Style::Regular;
  uint32_t floors = 1;
  // The paper's figures, for the whole building.
  uint32_t cells = 0;            // "rooms" in Table 1 = cells of the store
  uint32_t lights = 0;
  uint64_t triangles = 0;
  uint64_t maxTrianglesPerCell = 0;
  // Shape of the rooms.
  float roomDepth = 5.0f;
  float minRoomWidth = 3.5f, maxRoomWidth = 6.0f;
  float corridorHalfWidth = 1.0f;
};

// The preset named `name` (l-shape, z-building, octagon, soda-hall, tower);
// `floors` scales the tower (its figures are per floor) and must be 0
// (default) for the others. nullopt for an unknown name.
std::optional<BuildingPreset> findBuildingPreset(const std::string& name, uint32_t floors);
std::vector<std::string> buildingPresetNames();

}  // namespace portico
