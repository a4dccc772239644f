// `brute`: tests every triangle against every ray. O(n) per ray, no build.
// It is the reference the other accelerators are tested against, and a fine
// choice for cells of a few dozen triangles. No parameters.
#pragma once

#include <string_view>

#include "common/accel/accelerator.h"

namespace portico {

class BruteForce final : public Accelerator {
 public:
  // mesh's arrays must outlive this object.
  explicit BruteForce(const MeshView& mesh, std::string_view spec = "brute");

  Hit intersect(const Ray& ray) const override;
  bool occluded(const Ray& ray) const override;
  Bounds3 bounds() const override { return bounds_; }
  const AcceleratorStats& stats() const override { return stats_; }

 private:
  MeshView mesh_;
  Bounds3 bounds_;
  AcceleratorStats stats_;
};

}  // namespace portico
