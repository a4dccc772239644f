// A cell's photon map: the photons deposited in (and near) one cell, a
// kd-tree over their positions, exact k-nearest-neighbour queries and the
// radiance estimate the renderer takes at a hit point.
//
// Determinism: the constructor puts the photons in a canonical order (by a
// hash of every field, ties by every field) before building, so the tree,
// the photons' order and indices and every query result are bit-identical
// whatever order the photons arrived in (workers, batches, retries).
// Queries break distance ties by photon index.
//
// Layout: two flat arrays and no pointers. `photons_` holds the photons in
// the tree's leaf order (photon(i) is the i-th; the tree's slot i); `tree_`
// is a kd-tree with buckets over their positions (PointKdTree), so a search
// reads the photons of a leaf side by side. Both can be written out and
// read back as-is.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/math.h"
#include "common/transport/point_kd_tree.h"

namespace portico {

struct StoredPhoton {
  Vec3 position;
  // Unit, into the surface it landed on: the negated normal of the side it
  // arrived on (so dot(direction, n) < 0 for a query facing that side).
  Vec3 direction;
  Vec3 power;
  uint64_t pathId = 0;
  uint16_t bounce = 0;
};

class PhotonMap {
 public:
  // The most photons one map holds: node words keep 30 bits of index.
  static constexpr size_t kMaxPhotons = PointKdTree::kMaxPoints;
  // Cone filter constant k_c (Jensen): w = 1 - d / (k_c r). 1, the
  // sharpest cone, blurs least, and the reference scenes' error is mostly
  // the estimate's blur: a flat disc (box filter) has about twice the
  // cornell_closed block RMSE, a kernel with a negative lobe is noisier
  // (docs/image-quality.md).
  static constexpr float kConeFilter = 1.0f;
  // radiance() counts a photon whose surface's normal is within 120 degrees
  // of the query's: the far side of a thin wall (opposite normals) is left
  // out, a wall meeting the floor is not. The disc below keeps the wall's
  // photons to those near the corner, where they make up for the part of
  // the disc beyond the wall (leaving them out read a corner 2 % lower).
  static constexpr float kMostFacingAway = 0.5f;
  // Photons farther than this fraction of the search radius from the tangent
  // plane are ignored by radiance(): a flattened "disc" search, so thin walls
  // and corners do not leak light into each other.
  static constexpr float kDiscThickness = 0.25f;

  // Takes the photons, sorts them and builds the tree. Throws
  // std::invalid_argument when a position is not finite or there are more
  // than kMaxPhotons.
  explicit PhotonMap(std::vector<StoredPhoton> photons);

  size_t size() const { return photons_.size(); }
  bool empty() const { return photons_.empty(); }
  const StoredPhoton& photon(size_t i) const { return photons_[i]; }
  // Tight bounds of the photon positions (empty bounds for an empty map).
  const Bounds3& bounds() const { return bounds_; }

  // The k nearest photons to p with squared distance <= maxRadius^2, written
  // to `out` (cleared first) as indices for photon(i), nearest first; equal
  // distances in increasing index order. The squared distance is
  // dot(photon(i).position - p, photon(i).position - p) in float. Exact, not
  // approximate.
  //
  // Returns the squared radius of the region that holds the result and was
  // searched completely: the squared distance of the k-th (farthest) photon
  // when k were found, else maxRadius^2 (infinity for an infinite radius).
  // k == 0 returns 0 and leaves `out` empty.
  //
  // `radiusGuess` (optional) speeds up a run of queries at nearby points,
  // and changes no result: on entry a radius expected to hold about k
  // photons (0 for no guess), on return the radius of the result (the k-th
  // photon's distance, else maxRadius). With a guess, the search first
  // collects the photons within a little more than it and widens it when
  // they are fewer than k, instead of keeping a heap of the k nearest.
  //
  // Allocates nothing except growth of `out` and of thread-local buffers.
  float nearest(const Vec3& p, uint32_t k, float maxRadius, std::vector<uint32_t>& out,
                float* radiusGuess = nullptr) const;

  // Radiance reflected towards the viewer by a Lambertian surface with this
  // albedo at p, normal n (unit, on the viewer's side):
  //   L = albedo/pi * sum_i power_i * w_i / (norm * pi * r^2)
  // over the k nearest photons within maxRadius on a surface that does not
  // face away from n (dot(direction, n) < kMostFacingAway; others do not
  // count against k),
  // dropping those farther than kDiscThickness * r from the tangent plane.
  // w_i = 1 - d_i / (k_c r) is Jensen's cone filter, norm = 1 - 2 / (3 k_c).
  // r is the distance of the k-th photon when k were found, else maxRadius
  // (the whole disc was searched); for an infinite maxRadius and fewer than
  // k photons, the farthest found. Returns 0 when no photon is found or r is
  // 0 (all found photons sit exactly on p).
  //
  // `leftOut` (null, or one flag per photon) leaves out the photons flagged
  // non-zero, as if the map had none of them. `radiusGuess` as for
  // nearest(): the same bits with or without it.
  Vec3 radiance(const Vec3& p, const Vec3& n, const Vec3& albedo, uint32_t k, float maxRadius,
                const std::vector<uint8_t>* leftOut = nullptr, float* radiusGuess = nullptr) const;

  // Memory held by the map, in bytes.
  uint64_t bytes() const;

 private:
  // The k nearest accepted photons within maxRadiusSquared (k >= 1): their
  // candidate keys, in no particular order, in a thread-local buffer valid
  // until the thread's next query.
  struct Nearest {
    uint64_t* keys;
    uint32_t found;
    uint64_t farthest;   // the largest key, when found > 0
  };
  template <typename Accept>
  Nearest nearestKeys(const Vec3& p, uint32_t k, float maxRadiusSquared, Accept accept, float* radiusGuess) const;

  std::vector<StoredPhoton> photons_;
  PointKdTree tree_;
  Bounds3 bounds_;
};

}  // namespace portico
