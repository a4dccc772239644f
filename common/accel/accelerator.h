// The one interface of every per-cell acceleration structure.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "common/mesh_view.h"
#include "common/ray.h"

namespace portico {

// What a build reports (the paper's Table 3 uses averageDepth).
struct AcceleratorStats {
  std::string spec;
  double buildMs = 0;
  uint64_t nodes = 0;
  uint64_t leaves = 0;
  uint64_t emptyLeaves = 0;
  uint64_t triangleReferences = 0;
  double averageDepth = 0;   // over non-empty leaves
  uint32_t maxDepth = 0;
  uint64_t bytes = 0;
};

class Accelerator {
 public:
  virtual ~Accelerator() = default;
  // Nearest hit with ray.tMin < t < ray.tMax; ties broken by closerThan().
  virtual Hit intersect(const Ray& ray) const = 0;
  // Whether any hit exists with ray.tMin < t < ray.tMax.
  virtual bool occluded(const Ray& ray) const = 0;
  virtual Bounds3 bounds() const = 0;
  virtual const AcceleratorStats& stats() const = 0;
};

// A parsed accelerator spec such as "grid", "grid:res=64", "kd:sah".
struct AcceleratorSpec {
  std::string kind;                                      // "grid", "brute", ...
  std::string variant;                                   // "sah" in "kd:sah"
  std::vector<std::pair<std::string, std::string>> parameters;  // "res=64"
  std::string text;                                      // as the user typed it
};

// Throws std::invalid_argument naming the spec and what is wrong with it.
AcceleratorSpec parseAcceleratorSpec(std::string_view text);

// Builds the structure named by spec over mesh. The mesh arrays must outlive
// the returned accelerator. Throws std::invalid_argument for unknown kinds or
// parameters (naming them).
std::unique_ptr<Accelerator> buildAccelerator(const AcceleratorSpec& spec, const MeshView& mesh);

}  // namespace portico
