// Precomputed irradiance (Christensen, "Faster photon map global
// illumination", JGT 1999): once a cell's photon map is built, the
// photon-map estimate is taken once at a subset of its photons and stored
// with the normal of the surface each lies on. A final-gather ray's hit
// then reads the nearest point on a surface facing its way instead of
// searching k photons: one nearest-neighbour query in a tree `stride` times
// smaller, with buckets of points (nearest_point_tree.h).
//
// The subset is about one photon in `stride`, chosen by a hash of its index
// in the map, and each point's estimate uses only the other photons (scaled
// by stride / (stride - 1)). Estimated from the photons the points are
// drawn from, the nearest-point lookup is biased low (-2 % at k 64, -4 %
// at k 16, stride 4): a point in a sparse patch both reads low and is the
// nearest to more of the surface. Two disjoint random subsets of the
// photons are independent, and the bias goes (unit test).
//
// Determinism: the points, their values and every lookup depend only on
// the map (itself independent of arrival order), the stride, k and the
// radius; lookups break distance ties by point index.
//
// Photons copied across portals are in the map, so points near a doorway
// see both sides, as the estimate they replace does.
#pragma once

#include <cstdint>
#include <vector>

#include "common/math.h"
#include "common/transport/photon_map.h"
#include "common/transport/nearest_point_tree.h"

namespace portico {

class IrradianceCache {
 public:
  // A point is used for a hit facing n only when dot(its normal, n) reaches
  // this (within ~25 degrees: flat walls agree exactly, so this only
  // separates surfaces of different orientation) ...
  static constexpr float kMinNormalCosine = 0.9f;
  // ... and it lies within this fraction of its distance from the hit's
  // tangent plane (a box top does not stand in for the floor beside it).
  static constexpr float kMaxPlaneSlope = 0.25f;

  // Points at the photons isPoint() picks, each holding the estimate
  // map.radiance(position, normal, albedo 1, k, maxRadius) over the photons
  // it does not pick, scaled by stride / (stride - 1). stride >= 2.
  IrradianceCache(const PhotonMap& map, uint32_t stride, uint32_t k, float maxRadius);

  // Radiance per unit albedo leaving a Lambertian surface at p, facing n
  // (unit), read from the nearest compatible point within the radius given
  // at construction. False when there is none (the caller estimates).
  // `estimateRadius` (optional) receives the radius of the photon disc
  // that point's estimate averaged over: the scale of its blur.
  bool lookup(const Vec3& p, const Vec3& n, Vec3& radiancePerAlbedo, float* estimateRadius = nullptr) const;

  size_t size() const { return tree_.size(); }
  // Whether the map's photon of this index carries a point: one in
  // `stride` on average, by a hash of the index.
  static bool isPoint(uint32_t photon, uint32_t stride);
  uint64_t bytes() const;

 private:
  std::vector<Vec3> positions_;          // while building; then the tree's
  std::vector<Vec3> normals_, values_;   // in the tree's point order
  std::vector<float> radii_;             // each estimate's disc radius, in the same order
  NearestPointTree tree_;
  float maxRadiusSquared_ = 0;
};

}  // namespace portico
