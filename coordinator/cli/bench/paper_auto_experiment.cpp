// `portico bench paper`: `--accel auto` beside every fixed choice.
#include <fmt/format.h>

#include <map>
#include <string>
#include <vector>

#include "coordinator/cli/bench/paper_experiments.h"
#include "coordinator/cli/bench/paper_output.h"

namespace portico::cli::paper {

// auto_vs_fixed: `--accel auto` (a structure chosen per cell by the workers)
// beside every fixed choice. Until the pipeline knows `auto` its runs are
// refused; the experiment says so instead of failing.

void experimentAutoVsFixed(Bench& bench) {
  const Scale& scale = bench.scale();
  const std::vector<std::string> buildings = comparedBuildings(scale);
  Csv csv(concat({"building", "photons", "choice", "accel", "ratio_auto_over_this"}, kMeasurementColumns));
  std::vector<std::vector<std::string>> rows;
  BarPanel panel{fmt::format("--accel auto vs fixed choices, {}", scaleNote(bench, scale.photonsPerLight)),
                 "photon pass s", {}, {}};
  nlohmann::json summary = nlohmann::json::object();
  std::string autoStatus = "ok";
  for (const std::string& building : buildings) {
    const Store& store = bench.topological(building);
    const uint64_t photons = bench.photons(building, scale.photonsPerLight);
    const std::vector<SweepPoint> grids = gridSweep(bench, building);
    const SweepPoint* bestGrid = fastest(grids);
    std::vector<SweepPoint> fixed{{"grid", &bench.measure(store, "grid", photons)}};
    if (bestGrid) fixed.push_back(*bestGrid);
    fixed.push_back({"hgrid", &bench.measure(store, "hgrid", photons)});
    for (const SweepPoint& p : kdSweep(bench, store, photons)) fixed.push_back(p);
    fixed.push_back({"bvh", &bench.measure(store, "bvh", photons)});
    const SweepPoint* bestFixed = fastest(fixed);
    const Measurement& automatic = bench.measure(store, "auto", photons);
    const Measurement& embree = bench.measure(store, "embree", photons);
    if (!automatic.ok()) autoStatus = automatic.statusText();
    const double ratio = automatic.seconds() / secondsOf(bestFixed);
    BarGroup group{building, automatic.ok() ? fmt::format("auto/best x{:.2f}", ratio) : "auto " + automatic.statusText(),
                   {}};
    std::vector<std::string> row{building};
    for (const SweepPoint& p : fixed) {
      row.push_back(formatSeconds(p.m->seconds()));
      group.bars.push_back(timeBar(p.spec, p.m->seconds()));
      if (p.spec.rfind("grid:res=", 0) == 0) group.bars.back().color = kBestGridColor;   // apart from plain grid
      csv.row(concat({building, std::to_string(photons), &p == bestFixed ? "best_fixed" : "fixed", p.spec,
                      formatRatio(automatic.seconds() / p.m->seconds())},
                     measurementCells(*p.m)));
    }
    csv.row(concat({building, std::to_string(photons), "auto", "auto", "1"}, measurementCells(automatic)));
    csv.row(concat({building, std::to_string(photons), "baseline", "embree",
                    formatRatio(automatic.seconds() / embree.seconds())},
                   measurementCells(embree)));
    Bar autoBar = timeBar("auto", automatic.seconds());
    if (!automatic.ok()) autoBar.above = automatic.statusText() == "unavailable" ? "n/a" : "failed";
    group.bars.push_back(autoBar);
    group.bars.push_back(timeBar("embree", embree.seconds()));
    row.push_back(automatic.ok() ? formatSeconds(automatic.seconds()) : automatic.statusText());
    row.push_back(formatSeconds(embree.seconds()));
    row.push_back(specOf(bestFixed));
    row.push_back(formatRatio(ratio));
    row.push_back(acceleratorsText(automatic.ok() ? automatic.typical().accelerators : std::map<std::string, int64_t>{}));
    rows.push_back(row);
    panel.groups.push_back(group);
    summary[building] = {{"auto_status", automatic.statusText()},
                         {"auto_note", automatic.note},
                         {"auto_seconds", automatic.seconds()},
                         {"best_fixed", specOf(bestFixed)},
                         {"best_fixed_seconds", secondsOf(bestFixed)},
                         {"embree_seconds", embree.seconds()},
                         {"ratio_auto_over_best_fixed", ratio},
                         {"accelerators", automatic.ok() ? nlohmann::json(automatic.typical().accelerators)
                                                         : nlohmann::json::object()}};
  }
  for (const std::string s :
       {"grid", "grid:res=R (best)", "hgrid", "kd:median", "kd:sah", "kd:bbox", "bvh", "auto", "embree"})
    panel.legend.push_back({s, s == "grid:res=R (best)" ? kBestGridColor : structureColor(s)});
  printTable("auto_vs_fixed: photon pass (s) of --accel auto beside every fixed choice",
             {"building", "grid", "grid best R", "hgrid", "kd:median", "kd:sah", "kd:bbox", "bvh", "auto", "embree",
              "best fixed", "auto/best", "auto's choices"},
             rows,
             autoStatus == "ok" ? "auto's choices: the statistics' \"accelerators\" (spec=cells)"
                                : "auto is " + autoStatus + " in this build (the pipeline refused --accel auto)");
  csv.write(bench.out() / "auto_vs_fixed.csv");
  writeBarPlotPng((bench.out() / "auto_vs_fixed.png").string(), {panel}, 420 + 240 * int(buildings.size()), 480);
  bench.summary()["auto_vs_fixed"] = {{"auto_status", autoStatus}, {"per_building", summary}};
}


}  // namespace portico::cli::paper
