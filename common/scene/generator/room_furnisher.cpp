#include "common/scene/generator/room_furnisher.h"

#include <algorithm>
#include <cmath>

#include "common/scene/generator/demo_furniture.h"

namespace portico::furniture {

namespace {

constexpr float kWallGap = 0.02f;    // no face in a wall's plane
constexpr float kPieceGap = 0.05f;
constexpr float kMinDetail = 0.25f;
constexpr float kMaxDetail = 64.0f;

using demo::DemoRandom;

// The floor taken so far, and what must stay free.
class Floorplan {
 public:
  Floorplan(const FloorRect& area, const std::vector<FloorRect>& keepOut) : area_(area), taken_(keepOut) {}
  bool fits(const FloorRect& r) const {
    if (r.x0 < area_.x0 + kWallGap || r.x1 > area_.x1 - kWallGap || r.z0 < area_.z0 + kWallGap ||
        r.z1 > area_.z1 - kWallGap)
      return false;
    for (const FloorRect& t : taken_)
      if (r.overlaps(t, kPieceGap)) return false;
    return true;
  }
  // Places `spec` with its footprint's low corner at (x, z), turned; false if it does not fit.
  bool place(const PieceSpec& spec, float x, float z, int turns, float floorY, std::vector<PlacedPiece>& out) {
    const bool sideways = (turns & 1) != 0;
    const FloorRect r{x, x + (sideways ? spec.depth : spec.width), z, z + (sideways ? spec.width : spec.depth)};
    if (!fits(r)) return false;
    taken_.push_back(r);
    out.push_back(PlacedPiece{spec, Placement{Vec3(x, floorY, z), turns & 3}});
    return true;
  }
  const FloorRect& area() const { return area_; }

 private:
  FloorRect area_;
  std::vector<FloorRect> taken_;
};

PieceSpec randomPiece(Piece kind, DemoRandom& random) {
  PieceSpec p;
  p.kind = kind;
  p.variant = random.index(1u << 16);
  switch (kind) {
    case Piece::Desk: p.width = random.centimetres(1.2f, 1.6f), p.depth = random.centimetres(0.6f, 0.8f); break;
    case Piece::OfficeChair: p.width = p.depth = 0.62f; break;
    case Piece::DiningChair: p.width = p.depth = random.centimetres(0.42f, 0.48f); break;
    case Piece::RoundTable: p.width = p.depth = random.centimetres(0.8f, 1.2f); break;
    case Piece::Table:
      p.width = random.centimetres(1.0f, 2.0f), p.depth = random.centimetres(0.6f, 1.0f);
      p.height = random.chance(0.4f) ? 0.45f : 0.74f;
      break;
    case Piece::Sofa: p.width = random.centimetres(1.6f, 2.4f), p.depth = 0.88f; break;
    case Piece::Bed: p.width = random.centimetres(1.0f, 1.8f), p.depth = 2.1f; break;
    case Piece::Bookshelf:
      p.width = random.centimetres(0.8f, 1.4f), p.depth = 0.36f, p.height = random.centimetres(1.7f, 2.2f);
      break;
    case Piece::Cabinet:
      p.width = random.centimetres(0.6f, 1.2f), p.depth = 0.46f, p.height = random.centimetres(0.8f, 1.1f);
      break;
    case Piece::FloorLamp: p.width = p.depth = 0.46f, p.height = random.centimetres(1.5f, 1.8f); break;
    case Piece::Plant: p.width = p.depth = random.centimetres(0.4f, 0.7f), p.height = random.centimetres(0.7f, 1.5f); break;
  }
  return p;
}

// Offices: one workstation (desk, chair behind it) repeated in rows along
// x, every piece identical; a wall of shelves at the low-x side; plants in
// the free corners.
void arrangeRegular(Floorplan& plan, float floorY, DemoRandom& random, std::vector<PlacedPiece>& out) {
  const FloorRect& a = plan.area();
  PieceSpec shelf{Piece::Bookshelf, 1.0f, 0.36f, 2.0f, 7};
  for (float z = a.z0 + 0.3f; z + shelf.width < a.z1 - 0.3f; z += shelf.width + 0.06f)
    plan.place(shelf, a.x0 + kWallGap + 0.01f, z, 1, floorY, out);   // turned: its back to the wall
  const PieceSpec desk{Piece::Desk, 1.4f, 0.7f, 0.74f, 1};
  const PieceSpec chair{Piece::OfficeChair, 0.62f, 0.62f, 0.9f, 1};
  const float unitWidth = desk.width + 0.3f, unitDepth = desk.depth + 0.1f + chair.depth + 0.9f;
  for (float z = a.z0 + 0.5f; z + unitDepth < a.z1 - 0.3f; z += unitDepth)
    for (float x = a.x0 + 1.0f; x + unitWidth < a.x1 - 0.3f; x += unitWidth) {
      // Desk first, its chair behind it (toward -z, facing the desk).
      std::vector<PlacedPiece> unit;
      Floorplan trial = plan;
      if (!trial.place(desk, x, z + chair.depth + 0.1f, 0, floorY, unit)) continue;
      if (!trial.place(chair, x + 0.5f * (desk.width - chair.width), z, 2, floorY, unit)) continue;
      plan = trial;
      out.insert(out.end(), unit.begin(), unit.end());
    }
  const PieceSpec plantSpec{Piece::Plant, 0.55f, 0.55f, 1.2f, 3};
  for (float x : {a.x0 + 0.05f, a.x1 - 0.05f - plantSpec.width})
    for (float z : {a.z0 + 0.05f, a.z1 - 0.05f - plantSpec.depth}) plan.place(plantSpec, x, z, 0, floorY, out);
  (void)random;
}

// Hand-made: clusters around random centres, each of a theme, pieces of
// random sizes in random turns near their cluster's centre.
void arrangeHandMade(Floorplan& plan, float floorY, DemoRandom& random, std::vector<PlacedPiece>& out) {
  static const std::vector<std::vector<Piece>> kThemes = {
      {Piece::Sofa, Piece::Table, Piece::FloorLamp, Piece::Plant},
      {Piece::RoundTable, Piece::DiningChair, Piece::DiningChair, Piece::DiningChair, Piece::DiningChair},
      {Piece::Desk, Piece::OfficeChair, Piece::Bookshelf, Piece::Cabinet},
      {Piece::Bed, Piece::Cabinet, Piece::FloorLamp},
      {Piece::Plant, Piece::Plant, Piece::Bookshelf},
  };
  const FloorRect& a = plan.area();
  const float area = (a.x1 - a.x0) * (a.z1 - a.z0);
  const int clusters = std::max(1, int(area / random.uniform(6.0f, 14.0f)));
  for (int c = 0; c < clusters; ++c) {
    const std::vector<Piece>& theme = kThemes[random.index(uint32_t(kThemes.size()))];
    const float cx = random.uniform(a.x0, a.x1), cz = random.uniform(a.z0, a.z1);
    for (Piece kind : theme) {
      const PieceSpec spec = randomPiece(kind, random);
      for (int attempt = 0; attempt < 12; ++attempt) {
        const float x = cx + random.uniform(-1.6f, 1.6f) - 0.5f * spec.width;
        const float z = cz + random.uniform(-1.6f, 1.6f) - 0.5f * spec.depth;
        if (plan.place(spec, x, z, int(random.index(4)), floorY, out)) break;
      }
    }
  }
}

}  // namespace

std::vector<PlacedPiece> arrangeRoom(const FloorRect& area, float floorY, const std::vector<FloorRect>& keepOut,
                                     Style style, uint64_t seed) {
  DemoRandom random(seed);
  Floorplan plan(area, keepOut);
  std::vector<PlacedPiece> pieces;
  if (style == Style::Regular)
    arrangeRegular(plan, floorY, random, pieces);
  else
    arrangeHandMade(plan, floorY, random, pieces);
  return pieces;
}

uint64_t countTriangles(const std::vector<PlacedPiece>& pieces, float detail) {
  const Materials none;
  uint64_t total = 0;
  for (const PlacedPiece& piece : pieces) {
    Emitter counter = Emitter::counter(piece.spec.width, piece.spec.depth);
    emitPiece(counter, piece.spec, none, detail);
    total += counter.triangles();
  }
  return total;
}

float chooseDetail(std::vector<PlacedPiece>& pieces, uint64_t triangles) {
  while (!pieces.empty() && countTriangles(pieces, kMinDetail) > triangles) pieces.pop_back();
  if (pieces.empty() || triangles == 0) return kMinDetail;
  // Counts grow about as detail^2 (curves refine both ways): a few
  // square-root steps, keeping the closest.
  float detail = 1.0f, best = kMinDetail;
  double bestError = std::abs(double(countTriangles(pieces, kMinDetail)) - double(triangles));
  for (int step = 0; step < 8; ++step) {
    const uint64_t count = countTriangles(pieces, detail);
    const double error = std::abs(double(count) - double(triangles));
    if (error < bestError) bestError = error, best = detail;
    if (error < 0.01 * double(triangles)) break;
    detail = std::clamp(detail * float(std::sqrt(double(triangles) / double(std::max<uint64_t>(count, 1)))),
                        kMinDetail, kMaxDetail);
  }
  return best;
}

void emitRoom(MeshBuilder& mesh, const std::vector<PlacedPiece>& pieces, const Materials& materials, float detail) {
  for (const PlacedPiece& piece : pieces) {
    Emitter emitter(&mesh, piece.spec.width, piece.spec.depth, piece.placement);
    emitPiece(emitter, piece.spec, materials, detail);
  }
}

}  // namespace portico::furniture
