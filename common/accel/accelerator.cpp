// Accelerator specs: parsing ("kind[:variant,name=value,...]"), reading the
// parameters of one kind, and the table of kinds buildAccelerator knows.
#include "common/accel/accelerator.h"

#include <spdlog/spdlog.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "common/accel/brute_force.h"
#include "common/accel/bvh.h"
#include "common/accel/cost_model.h"
#include "common/accel/embree_accelerator.h"
#include "common/accel/hierarchical_grid.h"
#include "common/accel/kd_tree.h"
#include "common/accel/uniform_grid.h"

namespace portico {

namespace {

[[noreturn]] void failSpec(std::string_view text, std::string_view problem) {
  throw std::invalid_argument("accelerator spec '" + std::string(text) + "': " +
                              std::string(problem));
}

std::string_view trim(std::string_view s) {
  const auto isSpace = [](char c) { return c == ' ' || c == '\t'; };
  while (!s.empty() && isSpace(s.front())) s.remove_prefix(1);
  while (!s.empty() && isSpace(s.back())) s.remove_suffix(1);
  return s;
}

// One row per kind. create() reads the parameters, reports the unused ones
// and, when mesh is not null, builds; with a null mesh it only validates.
// New kinds add a row here.
struct AcceleratorKind {
  std::string_view name;
  std::unique_ptr<Accelerator> (*create)(AcceleratorParameters& parameters, const MeshView* mesh,
                                         std::string_view text);
};

constexpr AcceleratorKind kKinds[] = {
    {"brute",
     [](AcceleratorParameters& parameters, const MeshView* mesh,
        std::string_view text) -> std::unique_ptr<Accelerator> {
       parameters.reportUnused();
       if (!mesh) return nullptr;
       return std::make_unique<BruteForce>(*mesh, text);
     }},
    {"grid",
     [](AcceleratorParameters& parameters, const MeshView* mesh,
        std::string_view text) -> std::unique_ptr<Accelerator> {
       const UniformGridOptions options = readUniformGridOptions(parameters);
       parameters.reportUnused();
       if (!mesh) return nullptr;
       return std::make_unique<UniformGrid>(*mesh, options, text);
     }},
    {"hgrid",
     [](AcceleratorParameters& parameters, const MeshView* mesh,
        std::string_view text) -> std::unique_ptr<Accelerator> {
       const HierarchicalGridOptions options = readHierarchicalGridOptions(parameters);
       parameters.reportUnused();
       if (!mesh) return nullptr;
       return std::make_unique<HierarchicalGrid>(*mesh, options, text);
     }},
    {"kd",
     [](AcceleratorParameters& parameters, const MeshView* mesh,
        std::string_view text) -> std::unique_ptr<Accelerator> {
       const KdTreeOptions options = readKdTreeOptions(parameters);
       parameters.reportUnused();
       if (!mesh) return nullptr;
       return std::make_unique<KdTree>(*mesh, options, text);
     }},
    {"bvh",
     [](AcceleratorParameters& parameters, const MeshView* mesh,
        std::string_view text) -> std::unique_ptr<Accelerator> {
       const BvhOptions options = readBvhOptions(parameters);
       parameters.reportUnused();
       if (!mesh) return nullptr;
       return makeBvh(*mesh, options, text);
     }},
    // Resolved to a concrete spec by the cost model (cost_model.h). Workers
    // resolve `auto` themselves, per cell, from the rays the cell is expected
    // to trace; this entry serves direct builds (benchmarks, tests), where
    // rays=N says how many rays to plan for.
    {"auto",
     [](AcceleratorParameters& parameters, const MeshView* mesh,
        std::string_view) -> std::unique_ptr<Accelerator> {
       const double rays = parameters.positiveNumber("rays", 1e5);
       parameters.reportUnused();
       if (!mesh) return nullptr;
       const CostModel model = CostModel::loadDefault();
       const CostPrediction choice = model.choose(cellShape(*mesh), rays);
       return buildAccelerator(parseAcceleratorSpec(choice.candidate.spec), *mesh);
     }},
    {"embree",
     [](AcceleratorParameters& parameters, const MeshView* mesh,
        std::string_view text) -> std::unique_ptr<Accelerator> {
       const std::string quality = parameters.variant({"low", "medium", "high"}, "medium");
       parameters.reportUnused();
       if (!mesh) return nullptr;
       return std::make_unique<EmbreeAccelerator>(*mesh, text,
                                                  quality == "low"    ? EmbreeBuildQuality::Low
                                                  : quality == "high" ? EmbreeBuildQuality::High
                                                                      : EmbreeBuildQuality::Medium);
     }},
};

const AcceleratorKind& findKind(const AcceleratorSpec& spec) {
  for (const AcceleratorKind& kind : kKinds)
    if (kind.name == spec.kind) return kind;
  std::string known;
  for (const AcceleratorKind& kind : kKinds) known += (known.empty() ? "" : ", ") + std::string(kind.name);
  failSpec(spec.text, "unknown accelerator kind '" + spec.kind + "' (known kinds: " + known + ")");
}

}  // namespace

// ---------------------------------------------------------------------------
// Parsing

AcceleratorSpec parseAcceleratorSpec(std::string_view text) {
  AcceleratorSpec spec;
  spec.text = std::string(text);
  const size_t colon = text.find(':');
  spec.kind = std::string(trim(text.substr(0, colon)));
  if (spec.kind.empty()) failSpec(text, "no accelerator kind before ':' (e.g. 'grid:res=64')");
  if (colon == std::string_view::npos) return spec;

  std::string_view rest = text.substr(colon + 1);
  for (;;) {
    const size_t comma = rest.find(',');
    const std::string_view item = trim(rest.substr(0, comma));
    if (item.empty()) failSpec(text, "empty item in the list after ':'");
    const size_t equals = item.find('=');
    if (equals == std::string_view::npos) {
      if (!spec.variant.empty())
        failSpec(text, "two variants ('" + spec.variant + "' and '" + std::string(item) +
                           "'); parameters are written name=value");
      spec.variant = std::string(item);
    } else {
      const std::string name(trim(item.substr(0, equals)));
      const std::string value(trim(item.substr(equals + 1)));
      if (name.empty()) failSpec(text, "parameter without a name in '" + std::string(item) + "'");
      if (value.empty()) failSpec(text, "parameter " + name + " has no value");
      for (const auto& [existing, unused] : spec.parameters)
        if (existing == name) failSpec(text, "parameter " + name + " is given twice");
      spec.parameters.emplace_back(name, value);
    }
    if (comma == std::string_view::npos) break;
    rest.remove_prefix(comma + 1);
  }
  return spec;
}

// ---------------------------------------------------------------------------
// Building

std::unique_ptr<Accelerator> buildAccelerator(const AcceleratorSpec& spec, const MeshView& mesh) {
  AcceleratorParameters parameters(spec);
  std::unique_ptr<Accelerator> accelerator = findKind(spec).create(parameters, &mesh, spec.text);
  const AcceleratorStats& stats = accelerator->stats();
  spdlog::debug(
      "accelerator {}: {} triangles, {:.2f} ms, {} nodes, {} leaves ({} empty), {} references, "
      "depth {:.2f} avg {} max, {} bytes",
      stats.spec, mesh.triangleCount, stats.buildMs, stats.nodes, stats.leaves, stats.emptyLeaves,
      stats.triangleReferences, stats.averageDepth, stats.maxDepth, stats.bytes);
  return accelerator;
}

void validateAcceleratorSpec(const AcceleratorSpec& spec) {
  AcceleratorParameters parameters(spec);
  findKind(spec).create(parameters, nullptr, spec.text);
}

std::vector<std::string_view> acceleratorKinds() {
  std::vector<std::string_view> names;
  for (const AcceleratorKind& kind : kKinds) names.push_back(kind.name);
  return names;
}

// ---------------------------------------------------------------------------
// Parameters of one kind

AcceleratorParameters::AcceleratorParameters(const AcceleratorSpec& spec)
    : spec_(spec), used_(spec.parameters.size(), false) {}

void AcceleratorParameters::fail(std::string_view problem) const { failSpec(spec_.text, problem); }

const std::pair<std::string, std::string>* AcceleratorParameters::find(std::string_view name) {
  asked_.emplace_back(name);
  for (size_t i = 0; i < spec_.parameters.size(); ++i) {
    if (spec_.parameters[i].first == name) {
      used_[i] = true;
      return &spec_.parameters[i];
    }
  }
  return nullptr;
}

std::string AcceleratorParameters::variant(std::initializer_list<std::string_view> allowed,
                                           std::string_view defaultVariant) {
  variantRead_ = true;
  if (spec_.variant.empty()) return std::string(defaultVariant);
  for (std::string_view candidate : allowed)
    if (candidate == spec_.variant) return spec_.variant;
  std::string known;
  for (std::string_view candidate : allowed) known += (known.empty() ? "" : ", ") + std::string(candidate);
  fail("unknown variant '" + spec_.variant + "' for " + spec_.kind + " (known: " + known + ")");
}

int AcceleratorParameters::integer(std::string_view name, int defaultValue, int minimum,
                                   int maximum) {
  const auto* parameter = find(name);
  if (!parameter) return defaultValue;
  const std::string& text = parameter->second;
  const std::string expectation =
      minimum == 1 ? "a positive integer" : "an integer >= " + std::to_string(minimum);
  char* end = nullptr;
  errno = 0;
  const long value = std::strtol(text.c_str(), &end, 10);
  if (end == text.c_str() || *end != '\0' || errno == ERANGE || value < minimum)
    fail("parameter " + std::string(name) + " must be " + expectation + " (got '" + text + "')");
  if (value > maximum)
    fail("parameter " + std::string(name) + " must be at most " + std::to_string(maximum) +
         " (got " + text + ")");
  return static_cast<int>(value);
}

double AcceleratorParameters::positiveNumber(std::string_view name, double defaultValue) {
  const auto* parameter = find(name);
  if (!parameter) return defaultValue;
  const std::string& text = parameter->second;
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0' || errno == ERANGE || !std::isfinite(value) || value <= 0)
    fail("parameter " + std::string(name) + " must be a positive number (got '" + text + "')");
  return value;
}

void AcceleratorParameters::reportUnused() const {
  if (!variantRead_ && !spec_.variant.empty())
    fail(spec_.kind + " takes no variant (got '" + spec_.variant + "')");
  for (size_t i = 0; i < spec_.parameters.size(); ++i) {
    if (used_[i]) continue;
    std::string known;
    for (const std::string& name : asked_) known += (known.empty() ? "" : ", ") + name;
    fail("unknown parameter '" + spec_.parameters[i].first + "' for " + spec_.kind +
         (known.empty() ? " (it takes none)" : " (it takes: " + known + ")"));
  }
}

}  // namespace portico
