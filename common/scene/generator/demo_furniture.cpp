#include "common/scene/generator/demo_furniture.h"

#include <vector>

namespace portico::demo {

namespace {

// Pieces keep this far from walls, so that no face lies in a wall's plane
// (coplanar faces would make hits there depend on rounding).
constexpr float kWallGap = 0.01f;
constexpr float kPieceGap = 0.1f;   // between pieces' footprints

// A footprint in room coordinates (u along the corridor wall, v depth).
struct Footprint {
  float u0, u1, v0, v1;
  bool overlaps(const Footprint& o, float gap) const {
    return u0 < o.u1 + gap && o.u0 < u1 + gap && v0 < o.v1 + gap && o.v0 < v1 + gap;
  }
};

// Boxes in room coordinates, turned into world boxes by the frame.
class RoomPainter {
 public:
  RoomPainter(MeshBuilder& mesh, const RoomFrame& room) : mesh_(mesh), room_(room) {}
  // A box standing on the floor or on another box (no bottom face).
  void standing(float u0, float u1, float y0, float y1, float v0, float v1, uint32_t material) {
    mesh_.addBox(room_.toWorld(u0, u1, y0, y1, v0, v1), material, false);
  }
  // A box with open space below it (a table top, a shelf board).
  void raised(float u0, float u1, float y0, float y1, float v0, float v1, uint32_t material) {
    mesh_.addBox(room_.toWorld(u0, u1, y0, y1, v0, v1), material, true);
  }

 private:
  MeshBuilder& mesh_;
  const RoomFrame& room_;
};

// The pieces. Each fills the footprint it is given; y is up from the floor.

void bed(RoomPainter& paint, const Footprint& f, const DemoMaterials& m, DemoRandom& random) {
  const uint32_t fabric = m.fabrics[random.index(3)];
  const float headboard = f.v1 - 0.08f;
  paint.standing(f.u0, f.u1, 0.0f, 0.30f, f.v0, headboard, m.wood);                       // frame
  paint.standing(f.u0 + 0.03f, f.u1 - 0.03f, 0.30f, 0.50f, f.v0 + 0.03f, headboard - 0.02f, fabric);  // mattress
  paint.standing(f.u0 + 0.15f, f.u1 - 0.15f, 0.50f, 0.62f, headboard - 0.45f, headboard - 0.07f,
                 m.fabrics[2]);                                                            // pillow
  paint.standing(f.u0, f.u1, 0.0f, 1.0f, headboard, f.v1, m.darkWood);                     // headboard
}

void sofa(RoomPainter& paint, const Footprint& f, const DemoMaterials& m, DemoRandom& random) {
  const uint32_t fabric = m.fabrics[random.index(2)];
  const float arm = 0.18f, back = f.v1 - 0.2f;
  paint.standing(f.u0, f.u0 + arm, 0.0f, 0.62f, f.v0, back, fabric);
  paint.standing(f.u1 - arm, f.u1, 0.0f, 0.62f, f.v0, back, fabric);
  paint.standing(f.u0 + arm, f.u1 - arm, 0.0f, 0.42f, f.v0, back, fabric);
  paint.standing(f.u0, f.u1, 0.0f, 0.85f, back, f.v1, fabric);
}

void bookshelf(RoomPainter& paint, const Footprint& f, float height, const DemoMaterials& m, DemoRandom& random) {
  const float side = 0.03f, board = 0.03f;
  paint.standing(f.u0, f.u0 + side, 0.0f, height, f.v0, f.v1, m.darkWood);
  paint.standing(f.u1 - side, f.u1, 0.0f, height, f.v0, f.v1, m.darkWood);
  const int shelves = 4;
  const float pitch = (height - board) / shelves;
  for (int k = 0; k <= shelves; ++k) {
    const float y = k * pitch;
    if (k == 0)
      paint.standing(f.u0 + side, f.u1 - side, 0.0f, board, f.v0, f.v1, m.darkWood);
    else
      paint.raised(f.u0 + side, f.u1 - side, y, y + board, f.v0, f.v1, m.darkWood);
    if (k == shelves) break;
    // Books stand on the board, leaning on nothing: a row of thin boxes.
    for (float u = f.u0 + side + 0.02f;;) {
      const float thickness = random.centimetres(0.03f, 0.07f);
      if (u + thickness > f.u1 - side - 0.02f) break;
      const float bookHeight = std::min(random.centimetres(0.18f, 0.30f), pitch - board - 0.03f);
      if (random.chance(0.85f))
        paint.standing(u, u + thickness, y + board, y + board + bookHeight, f.v0 + 0.04f,
                       f.v0 + 0.04f + random.centimetres(0.18f, 0.24f), m.books[random.index(3)]);
      u += thickness + 0.005f;
    }
  }
}

void cabinet(RoomPainter& paint, const Footprint& f, float height, const DemoMaterials& m) {
  paint.standing(f.u0, f.u1, 0.0f, height, f.v0, f.v1, m.cabinet);
  paint.standing(f.u0 - 0.01f, f.u1 + 0.01f, height, height + 0.03f, f.v0 - 0.01f, f.v1 + 0.01f, m.wood);  // top
}

void table(RoomPainter& paint, const Footprint& f, const DemoMaterials& m) {
  const float top = 0.74f, slab = 0.04f, leg = 0.05f, inset = 0.04f;
  paint.raised(f.u0, f.u1, top - slab, top, f.v0, f.v1, m.wood);
  for (float u : {f.u0 + inset, f.u1 - inset - leg})
    for (float v : {f.v0 + inset, f.v1 - inset - leg}) paint.standing(u, u + leg, 0.0f, top - slab, v, v + leg, m.metal);
}

// A chair whose seat spans [u0, u0 + 0.44] x [v0, v0 + 0.44]; the backrest
// is on the side away from the table (backAtLowU: at u0).
void chair(RoomPainter& paint, float u0, float v0, bool backAtLowU, const DemoMaterials& m) {
  const float size = 0.44f, seat = 0.45f, slab = 0.04f, leg = 0.04f;
  paint.raised(u0, u0 + size, seat - slab, seat, v0, v0 + size, m.wood);
  for (float u : {u0, u0 + size - leg})
    for (float v : {v0, v0 + size - leg}) paint.standing(u, u + leg, 0.0f, seat - slab, v, v + leg, m.metal);
  const float backU = backAtLowU ? u0 : u0 + size - slab;
  paint.standing(backU, backU + slab, seat, seat + 0.45f, v0, v0 + size, m.wood);
}

// Seeded trial placement: a spot is accepted if it clears everything placed.
class Floorplan {
 public:
  Floorplan(const RoomFrame& room, float doorClearance) : room_(room), doorClearance_(doorClearance) {}
  bool fits(const Footprint& f) const {
    if (f.u0 < kWallGap || f.u1 > room_.width - kWallGap) return false;
    if (f.v0 < doorClearance_ || f.v1 > room_.depth - kWallGap) return false;
    for (const Footprint& taken : taken_)
      if (f.overlaps(taken, kPieceGap)) return false;
    return true;
  }
  void take(const Footprint& f) { taken_.push_back(f); }

 private:
  const RoomFrame& room_;
  float doorClearance_;
  std::vector<Footprint> taken_;
};

constexpr int kPlacementTries = 40;

}  // namespace

void furnishRoom(MeshBuilder& mesh, const RoomFrame& room, const DemoMaterials& materials, DemoRandom& random,
                 float doorClearance) {
  RoomPainter paint(mesh, room);
  Floorplan plan(room, doorClearance);
  const float backWall = room.depth - kWallGap;

  // The large piece against the back wall: a bed, a sofa or a bookshelf.
  const uint32_t kind = random.index(3);
  const float width = kind == 0 ? random.centimetres(1.2f, 1.6f)
                                : (kind == 1 ? random.centimetres(1.8f, 2.2f) : random.centimetres(0.9f, 1.5f));
  const float depth = kind == 0 ? 2.05f : (kind == 1 ? 0.85f : 0.35f);
  const float u0 = random.centimetres(0.2f, room.width - width - 0.2f);
  const Footprint back{u0, u0 + width, backWall - depth, backWall};
  plan.take(back);
  if (kind == 0) bed(paint, back, materials, random);
  if (kind == 1) sofa(paint, back, materials, random);
  if (kind == 2) bookshelf(paint, back, random.centimetres(1.8f, 2.1f), materials, random);

  // One or two cabinets against a side wall.
  const int cabinets = 1 + static_cast<int>(random.index(2));
  for (int c = 0; c < cabinets; ++c) {
    const float length = random.centimetres(0.6f, 1.2f), deep = random.centimetres(0.45f, 0.55f);
    const float height = random.centimetres(0.8f, 1.1f);
    for (int attempt = 0; attempt < kPlacementTries; ++attempt) {
      const bool left = random.chance(0.5f);
      const float v0 = random.centimetres(doorClearance, room.depth - length - kWallGap);
      const float uStart = left ? kWallGap + 0.01f : room.width - kWallGap - 0.01f - deep;
      const Footprint f{uStart, uStart + deep, v0, v0 + length};
      // The cabinet's top overhangs by 1 cm: test the footprint grown by it.
      if (!plan.fits(Footprint{f.u0 - 0.01f, f.u1 + 0.01f, f.v0 - 0.01f, f.v1 + 0.01f})) continue;
      plan.take(f);
      cabinet(paint, f, height, materials);
      break;
    }
  }

  // A table with a chair at each end, in the open floor.
  const float tableWidth = random.centimetres(1.0f, 1.5f), tableDepth = random.centimetres(0.7f, 0.9f);
  const float chairReach = 0.5f;   // a chair sticks out this far beyond the table's end
  for (int attempt = 0; attempt < kPlacementTries; ++attempt) {
    const float tu = random.centimetres(chairReach + kWallGap, room.width - tableWidth - chairReach - kWallGap);
    const float tv = random.centimetres(doorClearance, room.depth - tableDepth - kWallGap);
    const Footprint group{tu - chairReach, tu + tableWidth + chairReach, tv, tv + tableDepth};
    if (!plan.fits(group)) continue;
    plan.take(group);
    table(paint, Footprint{tu, tu + tableWidth, tv, tv + tableDepth}, materials);
    const float chairV = tv + 0.5f * tableDepth - 0.22f;
    chair(paint, tu - chairReach, chairV, true, materials);
    chair(paint, tu + tableWidth + chairReach - 0.44f, chairV, false, materials);
    break;
  }
}

}  // namespace portico::demo
