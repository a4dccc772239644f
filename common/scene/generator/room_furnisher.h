// Furnishes one room of a generated building for a triangle budget.
// arrangeRoom() decides which pieces go where (from the seed alone); then
// chooseDetail() finds the tessellation at which they make the room's
// budget, counting without building; emitRoom() builds them. Splitting the
// two is what lets a preset hit the paper's triangles per room while the
// furniture's layout stays the same at every scale.
#pragma once

#include <cstdint>
#include <vector>

#include "common/math.h"
#include "common/scene/generator/furniture_library.h"
#include "common/scene/generator/mesh_builder.h"

namespace portico::furniture {

// Regular: the same workstation repeated in rows, shelves along a wall,
// plants in the corners (automatically furnished offices: z-building,
// tower). HandMade: irregular clusters of varied pieces (a sofa corner, a
// dining group, a study, a bedroom) in random spots and turns (l-shape,
// octagon).
enum class Style : uint8_t { Regular, HandMade };

// An axis-aligned rectangle of floor in world x-z.
struct FloorRect {
  float x0 = 0, x1 = 0, z0 = 0, z1 = 0;
  bool overlaps(const FloorRect& o, float gap) const {
    return x0 < o.x1 + gap && o.x0 < x1 + gap && z0 < o.z1 + gap && o.z0 < z1 + gap;
  }
};

struct PlacedPiece {
  PieceSpec spec;
  Placement placement;
};

// Pieces for the floor `area` at height floorY, keeping clear of `keepOut`
// (the space in front of doors, stair openings).
std::vector<PlacedPiece> arrangeRoom(const FloorRect& area, float floorY, const std::vector<FloorRect>& keepOut,
                                     Style style, uint64_t seed);

uint64_t countTriangles(const std::vector<PlacedPiece>& pieces, float detail);

// The detail at which `pieces` come closest to `triangles`. When even the
// coarsest detail is over budget, pieces are dropped from the end first.
float chooseDetail(std::vector<PlacedPiece>& pieces, uint64_t triangles);

void emitRoom(MeshBuilder& mesh, const std::vector<PlacedPiece>& pieces, const Materials& materials, float detail);

}  // namespace portico::furniture
