// The machinery of `portico bench paper`'s experiments: the scene stores
// (generated, or re-cut into voxel cells, once), the measurements (each a
// real `portico render` child, pipeline_run.h), and the memo through which
// every experiment asks for them (Bench::measure), so that experiments that
// need the same run (the best grid of Fig. 5 in Fig. 9, the kd-trees of
// Fig. 8 in Fig. 9 and in auto_vs_fixed) share it and can also run alone.
#pragma once

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "common/util/temporary_directory.h"
#include "coordinator/cli/bench/accel_measure.h"
#include "coordinator/cli/bench/bench_paper.h"
#include "coordinator/cli/bench/paper_scale.h"
#include "coordinator/cli/bench/pipeline_run.h"

namespace portico::cli::paper {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline const std::vector<std::string> kKdHeuristics{"kd:median", "kd:sah", "kd:bbox"};

struct Store {
  std::string building;    // preset name
  uint32_t grid = 0;       // 0: topological cells; RG: uniform voxel cells
  std::string path;
  size_t cells = 0, nonEmptyCells = 0;
  uint64_t triangles = 0;
  size_t lights = 0;
  std::string label() const { return grid ? fmt::format("{} RG{}", building, grid) : building; }
};

// One measurement: every run of one (store, accel, photons, render) setting.
struct Measurement {
  enum class Status { Ok, Unavailable, Failed };
  Status status = Status::Ok;
  std::string note;                  // why not Ok: the child's message
  std::vector<PipelineRunStats> runs;
  std::vector<std::string> loads;    // 1-minute load average as each run started
  uint64_t photons = 0;

  bool ok() const { return status == Status::Ok && !runs.empty(); }
  // The run with the median photon phase (the lower middle one for an even count).
  const PipelineRunStats& typical() const {
    std::vector<size_t> order(runs.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(),
              [&](size_t a, size_t b) { return runs[a].photonSeconds < runs[b].photonSeconds; });
    return runs[order[(order.size() - 1) / 2]];
  }
  double seconds() const { return ok() ? medianOf(&PipelineRunStats::photonSeconds) : kNaN; }
  double buildSeconds() const { return ok() ? medianOf(&PipelineRunStats::buildSeconds) : kNaN; }
  double renderSeconds() const { return ok() ? medianOf(&PipelineRunStats::renderSeconds) : kNaN; }
  std::string statusText() const {
    return status == Status::Ok ? "ok" : status == Status::Unavailable ? "unavailable" : "failed";
  }

 private:
  double medianOf(double PipelineRunStats::*field) const {
    std::vector<double> values;
    for (const PipelineRunStats& run : runs) values.push_back(run.*field);
    return median(values);
  }
};

// What a render asks for beyond the photon pass.
struct RenderSetting {
  uint32_t spp = 1, gather = 0, width = 8, height = 8;   // the photon-pass-only token render
  bool operator<(const RenderSetting& o) const {
    return std::tie(spp, gather, width, height) < std::tie(o.spp, o.gather, o.width, o.height);
  }
};

// "accelerators" of the statistics ("kd:sah=12;grid=3"), empty when not reported.
std::string acceleratorsText(const std::map<std::string, int64_t>& accelerators);

// The CSV columns every pipeline measurement has, after the experiment's own,
// and a measurement's cells under them.
extern const std::vector<std::string> kMeasurementColumns;
std::vector<std::string> measurementCells(const Measurement& m);

// The bench: stores, the memo of measurements, the summary.
class Bench {
 public:
  Bench(const BenchPaperOptions& options, Scale scale);

  const Scale& scale() const { return scale_; }
  const std::filesystem::path& out() const { return out_; }
  nlohmann::json& summary() { return summary_; }

  // The generated building (topological cells), generated on first use and
  // kept under OUT/stores for later runs.
  const Store& topological(const std::string& building) { return store(building, 0); }
  // The same building re-cut into RG^3 voxel cells (`scene import --grid RG`).
  const Store& uniform(const std::string& building, uint32_t grid) { return store(building, grid); }

  // Photons of a pass over `building`: photons per light x the generated
  // building's lights (the uniform stores get the same count).
  uint64_t photons(const std::string& building, uint64_t perLight) {
    return perLight * std::max<size_t>(1, topological(building).lights);
  }

  // The photon pass (and render) of `store` with `accel`, run once per
  // setting however many experiments ask for it.
  const Measurement& measure(const Store& store, const std::string& accel, uint64_t photons,
                             const RenderSetting& render = {});

  // OUT/summary.json; throws std::runtime_error when it cannot be written.
  void writeSummary() const;

 private:
  const Store& store(const std::string& building, uint32_t grid);
  void generate(const Store& s);
  void importUniform(const Store& s);
  // One run into m; false when the setting cannot run (no point repeating it).
  bool runOnce(const Store& store, const std::string& accel, uint64_t photons, const RenderSetting& render,
               Measurement& m);

  const BenchPaperOptions& options_;
  Scale scale_;
  std::filesystem::path out_;
  TemporaryDirectory work_{"portico-bench-paper"};
  std::map<std::pair<std::string, uint32_t>, Store> stores_;
  std::map<std::tuple<std::string, std::string, uint64_t, RenderSetting>, Measurement> memo_;
  size_t runCount_ = 0;
  nlohmann::json summary_ = nlohmann::json::object();
};

// Shared sweeps: the best grid resolution and the kd heuristics of a
// building, asked for by several experiments.
struct SweepPoint {
  std::string spec;
  const Measurement* m = nullptr;
};

// grid:res=R for every R of the scale, photonsPerLight per light.
std::vector<SweepPoint> gridSweep(Bench& bench, const std::string& building);
// The three kd heuristics on store.
std::vector<SweepPoint> kdSweep(Bench& bench, const Store& store, uint64_t photons);
// The fastest of points (nullptr when none ran).
const SweepPoint* fastest(const std::vector<SweepPoint>& points);
inline double secondsOf(const SweepPoint* p) { return p ? p->m->seconds() : kNaN; }
inline std::string specOf(const SweepPoint* p) { return p ? p->spec : "n/a"; }

// "N photons/light (paper M)": the scale's count beside the paper's.
std::string scaleNote(const Bench& bench, uint64_t perLight);

}  // namespace portico::cli::paper
