// A library of tessellated furniture for generated buildings: desks, office
// and dining chairs, round and rectangular tables, sofas, beds, bookshelves,
// cabinets, floor and desk lamps, plants. Curved parts (legs, cushions,
// lamp shades, pots, leaves) are real surfaces whose tessellation grows with
// `detail`, so a room's triangle count comes from finely modelled pieces,
// as in a furnished architectural model, not from subdivided walls.
//
// Each piece is modelled in its own frame: footprint [0, width] x [0, depth]
// in (x, z), standing on y = 0, its front (where one sits or reaches) toward
// -z. A Placement turns it by quarter turns and puts it on a floor.
#pragma once

#include <cstdint>
#include <functional>

#include "common/math.h"
#include "common/scene/generator/mesh_builder.h"

namespace portico::furniture {

struct Materials {
  uint32_t wood = 0, darkWood = 0, metal = 0, white = 0, screen = 0;
  uint32_t fabrics[3] = {0, 0, 0};
  uint32_t books[3] = {0, 0, 0};
  uint32_t leaf = 0, pot = 0;
};

// Where a piece goes: its footprint's world corner of least x and z, the
// floor height, and quarter turns about +y (0..3). A turned piece's world
// footprint is depth x width.
struct Placement {
  Vec3 corner;
  int quarterTurns = 0;
};

// Turns piece-frame geometry into world geometry in a MeshBuilder, or only
// counts the triangles it would make (countOnly), so a room can choose its
// detail for a triangle budget without building the meshes.
class Emitter {
 public:
  Emitter(MeshBuilder* mesh, float width, float depth, const Placement& placement)
      : mesh_(mesh), width_(width), depth_(depth), placement_(placement) {}
  static Emitter counter(float width, float depth) { return Emitter(nullptr, width, depth, Placement{}); }

  Vec3 toWorld(const Vec3& p) const;
  void box(const Bounds3& local, uint32_t material, bool withBottom);
  void surface(int columns, int rows, bool wrapS, const std::function<Vec3(float, float)>& point, uint32_t material);
  uint64_t triangles() const { return triangles_; }

 private:
  MeshBuilder* mesh_;
  float width_, depth_;
  Placement placement_;
  uint64_t triangles_ = 0;
};

// Segments for a curve that has `base` segments at detail 1 (at least `min`).
int segments(float detail, int base, int min = 3);

// The pieces. Sizes are in metres; each fills [0, width] x [0, depth].
// `variant` varies colours and small details deterministically.
enum class Piece : uint8_t {
  Desk, OfficeChair, DiningChair, RoundTable, Table, Sofa, Bed, Bookshelf, Cabinet, FloorLamp, Plant,
};
constexpr int kPieceKinds = 11;

struct PieceSpec {
  Piece kind = Piece::Table;
  float width = 1, depth = 1, height = 0.75f;
  uint32_t variant = 0;
};

// Emits one piece at the given detail (>= 0.25).
void emitPiece(Emitter& emitter, const PieceSpec& piece, const Materials& materials, float detail);

}  // namespace portico::furniture
