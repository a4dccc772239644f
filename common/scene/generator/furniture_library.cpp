#include "common/scene/generator/furniture_library.h"

#include <algorithm>
#include <cmath>

namespace portico::furniture {

namespace {

constexpr float kTwoPi = 6.28318530718f;

struct Vec2f {
  float x, y;
};

// A surface of revolution about the vertical axis through (cx, cz):
// profile(t) gives (radius, height) for t in [0, 1], bottom to top. Angles
// run clockwise seen from above so that fronts face outward.
void lathe(Emitter& e, float cx, float cz, int around, int rows, const std::function<Vec2f(float)>& profile,
           uint32_t material) {
  e.surface(around, rows, true,
            [&](float s, float t) {
              const Vec2f rh = profile(t);
              const float angle = -kTwoPi * s;
              return Vec3(cx + rh.x * std::cos(angle), rh.y, cz + rh.x * std::sin(angle));
            },
            material);
}

void cylinder(Emitter& e, float cx, float cz, float radius, float y0, float y1, float detail, uint32_t material) {
  lathe(e, cx, cz, segments(detail, 8), 1, [&](float t) { return Vec2f{radius, y0 + t * (y1 - y0)}; }, material);
}

// A rounded cushion: a superellipsoid with half-sizes `half` about `center`
// (exponent 0.3: nearly a box with soft edges). The poles keep a few
// millimetres of radius so no triangle degenerates.
void cushion(Emitter& e, const Vec3& center, const Vec3& half, float detail, uint32_t material) {
  const int around = segments(detail, 12, 4), rows = segments(detail, 6, 3);
  const auto signedPower = [](float v, float p) { return std::copysign(std::pow(std::abs(v), p), v); };
  e.surface(around, rows, true,
            [&](float s, float t) {
              const float latitude = (t - 0.5f) * 3.12f;   // just short of +-pi/2
              const float longitude = -kTwoPi * s;
              const float c = signedPower(std::cos(latitude), 0.3f);
              return Vec3(center.x + half.x * c * signedPower(std::cos(longitude), 0.3f),
                          center.y + half.y * signedPower(std::sin(latitude), 0.3f),
                          center.z + half.z * c * signedPower(std::sin(longitude), 0.3f));
            },
            material);
}

// A leaf: a strip from `base` along heading `angle` (radians, in x-z), rising
// then drooping, widest in the middle.
void leaf(Emitter& e, const Vec3& base, float angle, float length, float width, float rise, float detail,
          uint32_t material) {
  const Vec3 along(std::cos(angle), 0.0f, std::sin(angle));
  const Vec3 side(-along.z, 0.0f, along.x);
  e.surface(segments(detail, 2, 1), segments(detail, 5, 2), false,
            [&](float s, float t) {
              const float halfWidth = 0.5f * width * std::sin(3.14159265f * std::max(0.02f, std::min(0.98f, t)));
              const float height = rise * (2.0f * t - 1.4f * t * t);
              return base + along * (length * t) + Vec3(0.0f, height, 0.0f) + side * ((2.0f * s - 1.0f) * halfWidth);
            },
            material);
}

void desk(Emitter& e, const PieceSpec& p, const Materials& m, float detail) {
  const float w = p.width, d = p.depth, top = 0.74f;
  e.box(Bounds3(Vec3(0, top - 0.03f, 0), Vec3(w, top, d)), m.wood, true);
  e.box(Bounds3(Vec3(0.02f, 0, 0.05f), Vec3(0.05f, top - 0.03f, d - 0.05f)), m.white, false);
  e.box(Bounds3(Vec3(w - 0.05f, 0, 0.05f), Vec3(w - 0.02f, top - 0.03f, d - 0.05f)), m.white, false);
  e.box(Bounds3(Vec3(0.05f, 0.3f, d - 0.06f), Vec3(w - 0.05f, top - 0.03f, d - 0.04f)), m.white, true);
  // Monitor on a turned stand, keyboard, and a desk lamp in the corner.
  const float mx = 0.5f * w, mz = d - 0.2f;
  lathe(e, mx, mz, segments(detail, 10), segments(detail, 3, 1),
        [&](float t) { return Vec2f{0.11f - 0.08f * std::min(1.0f, t * 3.0f), top + 0.33f * t}; }, m.metal);
  e.box(Bounds3(Vec3(mx - 0.3f, top + 0.12f, mz - 0.06f), Vec3(mx + 0.3f, top + 0.48f, mz - 0.03f)), m.screen, true);
  e.box(Bounds3(Vec3(mx - 0.22f, top, 0.12f), Vec3(mx + 0.22f, top + 0.02f, 0.28f)), m.white, false);
  const float lx = w - 0.15f, lz = d - 0.15f;
  lathe(e, lx, lz, segments(detail, 10), segments(detail, 2, 1),
        [&](float t) { return Vec2f{0.08f - 0.06f * t, top + 0.03f * t}; }, m.metal);
  cylinder(e, lx, lz, 0.012f, top + 0.03f, top + 0.42f, detail, m.metal);
  lathe(e, lx, lz, segments(detail, 12), segments(detail, 3, 1),
        [&](float t) { return Vec2f{0.13f - 0.07f * t, top + 0.36f + 0.14f * t}; }, m.fabrics[p.variant % 3]);
}

void officeChair(Emitter& e, const PieceSpec& p, const Materials& m, float detail) {
  const float cx = 0.5f * p.width, cz = 0.5f * p.depth;
  const float reach = 0.45f * std::min(p.width, p.depth);
  for (int leg = 0; leg < 5; ++leg) {   // a five-star base on casters
    const float angle = kTwoPi * float(leg) / 5.0f;
    const Vec3 tip(cx + reach * std::cos(angle), 0.05f, cz + reach * std::sin(angle));
    cylinder(e, 0.5f * (cx + tip.x), 0.5f * (cz + tip.z), 0.025f, 0.06f, 0.1f, detail, m.metal);
    cushion(e, tip, Vec3(0.03f, 0.03f, 0.03f), detail * 0.5f, m.metal);
  }
  cylinder(e, cx, cz, 0.03f, 0.08f, 0.42f, detail, m.metal);
  const uint32_t fabric = m.fabrics[p.variant % 3];
  cushion(e, Vec3(cx, 0.46f, cz), Vec3(0.24f, 0.05f, 0.23f), detail, fabric);
  cushion(e, Vec3(cx, 0.78f, p.depth - 0.08f), Vec3(0.22f, 0.26f, 0.045f), detail, fabric);
}

void diningChair(Emitter& e, const PieceSpec& p, const Materials& m, float detail) {
  const float w = p.width, d = p.depth, seat = 0.45f;
  for (float x : {0.04f, w - 0.04f})
    for (float z : {0.04f, d - 0.04f}) cylinder(e, x, z, 0.018f, 0.0f, seat - 0.03f, detail, m.wood);
  e.box(Bounds3(Vec3(0, seat - 0.03f, 0), Vec3(w, seat, d)), m.wood, true);
  cushion(e, Vec3(0.5f * w, seat + 0.02f, 0.5f * d), Vec3(0.5f * w - 0.03f, 0.025f, 0.5f * d - 0.03f), detail,
          m.fabrics[p.variant % 3]);
  for (float x : {0.02f, w - 0.05f}) e.box(Bounds3(Vec3(x, seat, d - 0.04f), Vec3(x + 0.03f, seat + 0.5f, d)), m.wood, false);
  for (int slat = 0; slat < 3; ++slat) {
    const float y = seat + 0.2f + 0.12f * float(slat);
    e.box(Bounds3(Vec3(0.05f, y, d - 0.035f), Vec3(w - 0.05f, y + 0.05f, d - 0.005f)), m.wood, true);
  }
}

void roundTable(Emitter& e, const PieceSpec& p, const Materials& m, float detail) {
  const float cx = 0.5f * p.width, cz = 0.5f * p.depth, radius = 0.5f * std::min(p.width, p.depth), top = 0.74f;
  // Top: from the underside's centre out to a rounded rim and back in on top.
  lathe(e, cx, cz, segments(detail, 24), segments(detail, 4, 2),
        [&](float t) {
          const float angle = 3.14159265f * t;   // around the rim, underside to top
          if (t < 0.2f) return Vec2f{0.01f + (radius - 0.03f) * (t / 0.2f), top - 0.04f};
          if (t > 0.8f) return Vec2f{0.01f + (radius - 0.03f) * ((1.0f - t) / 0.2f), top};
          return Vec2f{radius - 0.02f + 0.02f * std::sin(angle), top - 0.02f - 0.02f * std::cos(angle)};
        },
        m.wood);
  lathe(e, cx, cz, segments(detail, 12), segments(detail, 6, 2),
        [&](float t) {
          const float y = t * (top - 0.04f);
          const float r = t < 0.1f ? 0.25f - 1.8f * t : 0.06f + 0.03f * std::sin(9.0f * t);
          return Vec2f{r, y};
        },
        m.darkWood);
}

void table(Emitter& e, const PieceSpec& p, const Materials& m, float detail) {
  const float w = p.width, d = p.depth, top = p.height;
  e.box(Bounds3(Vec3(0, top - 0.04f, 0), Vec3(w, top, d)), m.wood, true);
  for (float x : {0.07f, w - 0.07f})
    for (float z : {0.07f, d - 0.07f})
      lathe(e, x, z, segments(detail, 8), segments(detail, 4, 1),
            [&](float t) { return Vec2f{0.035f - 0.012f * t + 0.006f * std::sin(12.0f * t), (top - 0.04f) * t}; },
            m.darkWood);
}

void sofa(Emitter& e, const PieceSpec& p, const Materials& m, float detail) {
  const float w = p.width, d = p.depth, arm = 0.16f;
  const uint32_t fabric = m.fabrics[p.variant % 3];
  e.box(Bounds3(Vec3(arm, 0.08f, 0), Vec3(w - arm, 0.3f, d)), m.darkWood, true);
  for (float x : {0.1f, w - 0.1f}) {
    for (float z : {0.08f, d - 0.08f}) cylinder(e, x, z, 0.025f, 0.0f, 0.08f, detail, m.metal);
    cushion(e, Vec3(x < 0.5f * w ? 0.5f * arm : w - 0.5f * arm, 0.42f, 0.5f * d), Vec3(0.5f * arm, 0.2f, 0.5f * d),
            detail, fabric);
  }
  const int seats = std::max(1, int((w - 2 * arm) / 0.6f));
  const float seatWidth = (w - 2 * arm) / float(seats);
  for (int s = 0; s < seats; ++s) {
    const float cx = arm + seatWidth * (float(s) + 0.5f);
    cushion(e, Vec3(cx, 0.38f, 0.42f * d), Vec3(0.48f * seatWidth, 0.08f, 0.4f * d), detail, fabric);
    cushion(e, Vec3(cx, 0.62f, d - 0.11f), Vec3(0.48f * seatWidth, 0.24f, 0.1f), detail, fabric);
  }
}

void bed(Emitter& e, const PieceSpec& p, const Materials& m, float detail) {
  const float w = p.width, d = p.depth;
  e.box(Bounds3(Vec3(0, 0.1f, 0), Vec3(w, 0.3f, d - 0.06f)), m.wood, true);
  for (float x : {0.05f, w - 0.05f})
    for (float z : {0.05f, d - 0.11f}) cylinder(e, x, z, 0.03f, 0.0f, 0.1f, detail, m.darkWood);
  e.box(Bounds3(Vec3(0, 0, d - 0.06f), Vec3(w, 1.0f, d)), m.darkWood, false);
  cushion(e, Vec3(0.5f * w, 0.4f, 0.5f * (d - 0.06f)), Vec3(0.5f * w - 0.02f, 0.1f, 0.5f * (d - 0.06f) - 0.02f),
          detail * 1.5f, m.fabrics[p.variant % 3]);
  const int pillows = w > 1.2f ? 2 : 1;
  for (int k = 0; k < pillows; ++k)
    cushion(e, Vec3(w * (float(k) + 0.5f) / float(pillows), 0.55f, d - 0.35f), Vec3(0.3f, 0.07f, 0.2f), detail,
            m.fabrics[2]);
}

void bookshelf(Emitter& e, const PieceSpec& p, const Materials& m, float detail) {
  const float w = p.width, d = p.depth, h = p.height, side = 0.03f, board = 0.03f;
  e.box(Bounds3(Vec3(0, 0, 0), Vec3(side, h, d)), m.darkWood, false);
  e.box(Bounds3(Vec3(w - side, 0, 0), Vec3(w, h, d)), m.darkWood, false);
  e.box(Bounds3(Vec3(side, 0, d - 0.01f), Vec3(w - side, h, d)), m.darkWood, false);
  const int shelves = std::max(2, int(h / 0.38f));
  const float pitch = (h - board) / float(shelves);
  uint32_t state = p.variant * 2654435761u + 12345u;
  const auto next = [&]() { state = state * 1664525u + 1013904223u; return float(state >> 8) * 0x1.0p-24f; };
  for (int k = 0; k <= shelves; ++k) {
    const float y = float(k) * pitch;
    e.box(Bounds3(Vec3(side, y, 0), Vec3(w - side, y + board, d - 0.01f)), m.darkWood, k > 0);
    if (k == shelves) break;
    for (float x = side + 0.01f;;) {   // books: thin boxes with rounded spines on the finer models
      const float thickness = 0.025f + 0.04f * next();
      if (x + thickness > w - side - 0.01f) break;
      const float height = std::min(0.18f + 0.12f * next(), pitch - board - 0.02f);
      const uint32_t colour = m.books[uint32_t(next() * 3.0f) % 3];
      if (detail >= 2.0f)
        lathe(e, x + 0.5f * thickness, 0.05f + 0.5f * thickness, segments(detail, 4), 1,
              [&](float t) { return Vec2f{0.5f * thickness, y + board + height * t}; }, colour);
      else
        e.box(Bounds3(Vec3(x, y + board, 0.04f), Vec3(x + thickness, y + board + height, d - 0.03f)), colour, false);
      x += thickness + 0.004f;
    }
  }
}

void cabinet(Emitter& e, const PieceSpec& p, const Materials& m, float detail) {
  const float w = p.width, d = p.depth, h = p.height;
  // The body stands 4 cm back so that the top's overhang and the knobs stay on the footprint.
  e.box(Bounds3(Vec3(0.01f, 0, 0.04f), Vec3(w - 0.01f, h, d - 0.01f)), m.white, false);
  e.box(Bounds3(Vec3(0, h, 0.03f), Vec3(w, h + 0.03f, d)), m.wood, true);
  const int doors = std::max(1, int(w / 0.45f));
  for (int k = 0; k < doors; ++k) {   // a round knob per door, on the front (-z)
    const float x = w * (float(k) + 0.5f) / float(doors);
    cushion(e, Vec3(x, 0.75f * h, 0.02f), Vec3(0.015f, 0.015f, 0.015f), detail * 0.5f, m.metal);
  }
}

void floorLamp(Emitter& e, const PieceSpec& p, const Materials& m, float detail) {
  const float cx = 0.5f * p.width, cz = 0.5f * p.depth, h = p.height;
  lathe(e, cx, cz, segments(detail, 16), segments(detail, 3, 1),
        [&](float t) { return Vec2f{0.16f - 0.13f * t, 0.04f * std::sin(1.57f * t)}; }, m.metal);
  cylinder(e, cx, cz, 0.012f, 0.03f, h - 0.3f, detail, m.metal);
  lathe(e, cx, cz, segments(detail, 16), segments(detail, 4, 1),
        [&](float t) { return Vec2f{0.22f - 0.1f * t, h - 0.35f + 0.3f * t}; }, m.fabrics[2]);
}

void plant(Emitter& e, const PieceSpec& p, const Materials& m, float detail) {
  const float cx = 0.5f * p.width, cz = 0.5f * p.depth, radius = 0.4f * std::min(p.width, p.depth);
  const float potHeight = 0.35f * p.height;
  lathe(e, cx, cz, segments(detail, 14), segments(detail, 4, 1),
        [&](float t) { return Vec2f{radius * (0.7f + 0.3f * t) + 0.01f * std::sin(6.0f * t), potHeight * t}; }, m.pot);
  const int leaves = 8 + int(p.variant % 5);
  for (int k = 0; k < leaves; ++k) {
    const float angle = kTwoPi * (float(k) / float(leaves)) + 0.37f * float(p.variant % 7);
    const float tier = float(k % 3) / 3.0f;
    // Leaves reach at most to the footprint's edge (their width adds a little).
    leaf(e, Vec3(cx, potHeight + tier * 0.3f * p.height, cz), angle,
         (0.5f * std::min(p.width, p.depth) - 0.06f) * (1.0f - 0.3f * tier), 0.1f + 0.02f * tier, 0.5f * p.height,
         detail, m.leaf);
  }
}

}  // namespace

int segments(float detail, int base, int min) {
  return std::max(min, int(std::lround(double(base) * double(detail))));
}

Vec3 Emitter::toWorld(const Vec3& p) const {
  float x = p.x, z = p.z;
  switch (placement_.quarterTurns & 3) {   // proper rotations about +y: windings keep their fronts
    case 1: x = p.z, z = width_ - p.x; break;
    case 2: x = width_ - p.x, z = depth_ - p.z; break;
    case 3: x = depth_ - p.z, z = p.x; break;
    default: break;
  }
  return placement_.corner + Vec3(x, p.y, z);
}

void Emitter::box(const Bounds3& local, uint32_t material, bool withBottom) {
  triangles_ += withBottom ? 12 : 10;
  if (!mesh_) return;
  const Vec3 a = toWorld(local.lo), b = toWorld(local.hi);
  mesh_->addBox(Bounds3(min(a, b), max(a, b)), material, withBottom);
}

void Emitter::surface(int columns, int rows, bool wrapS, const std::function<Vec3(float, float)>& point,
                      uint32_t material) {
  triangles_ += uint64_t(2) * uint64_t(columns) * uint64_t(rows);
  if (!mesh_) return;
  mesh_->addSurface(columns, rows, wrapS, [&](float s, float t) { return toWorld(point(s, t)); }, material);
}

void emitPiece(Emitter& e, const PieceSpec& piece, const Materials& m, float detail) {
  detail = std::max(0.25f, detail);
  switch (piece.kind) {
    case Piece::Desk: desk(e, piece, m, detail); break;
    case Piece::OfficeChair: officeChair(e, piece, m, detail); break;
    case Piece::DiningChair: diningChair(e, piece, m, detail); break;
    case Piece::RoundTable: roundTable(e, piece, m, detail); break;
    case Piece::Table: table(e, piece, m, detail); break;
    case Piece::Sofa: sofa(e, piece, m, detail); break;
    case Piece::Bed: bed(e, piece, m, detail); break;
    case Piece::Bookshelf: bookshelf(e, piece, m, detail); break;
    case Piece::Cabinet: cabinet(e, piece, m, detail); break;
    case Piece::FloorLamp: floorLamp(e, piece, m, detail); break;
    case Piece::Plant: plant(e, piece, m, detail); break;
  }
}

}  // namespace portico::furniture
