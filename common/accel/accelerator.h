// The one interface of every per-cell acceleration structure.
#pragma once

#include <cstdint>
#include <initializer_list>
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

// Checks kind, variant and parameters as buildAccelerator would, without
// building: lets a coordinator refuse a bad --accel before any work starts.
void validateAcceleratorSpec(const AcceleratorSpec& spec);

// The kinds buildAccelerator knows, in the order they are listed to users.
std::vector<std::string_view> acceleratorKinds();

// Reads one spec's variant and parameters for the kind that builds it, and
// remembers what was read, so that a misspelt or foreign parameter becomes an
// error naming it (after pbrt's ParameterDictionary::ReportUnused).
class AcceleratorParameters {
 public:
  explicit AcceleratorParameters(const AcceleratorSpec& spec);

  // The variant if one of `allowed`, defaultVariant if none was given.
  std::string variant(std::initializer_list<std::string_view> allowed,
                      std::string_view defaultVariant);
  // An integer in [minimum, maximum]; defaultValue when the parameter is absent.
  int integer(std::string_view name, int defaultValue, int minimum, int maximum);
  // A finite number > 0; defaultValue when the parameter is absent.
  double positiveNumber(std::string_view name, double defaultValue);
  // Throws if a parameter was never read, or a variant was given but never read.
  void reportUnused() const;

  // Throws std::invalid_argument "accelerator spec '<text>': <problem>".
  [[noreturn]] void fail(std::string_view problem) const;

 private:
  const std::pair<std::string, std::string>* find(std::string_view name);

  const AcceleratorSpec& spec_;
  std::vector<bool> used_;
  std::vector<std::string> asked_;  // parameter names the kind reads, for error messages
  bool variantRead_ = false;
};

}  // namespace portico
