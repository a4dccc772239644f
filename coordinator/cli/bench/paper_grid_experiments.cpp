// `portico bench paper`: the experiments on the grids, Figs. 4-6.
#include <fmt/format.h>

#include <string>
#include <vector>

#include "coordinator/cli/bench/paper_experiments.h"
#include "coordinator/cli/bench/paper_output.h"

namespace portico::cli::paper {

// Figs. 4 and 5: total photon-pass time against the uniform grid's
// resolution, per building; Embree as a flat baseline.

void experimentGridResolution(Bench& bench) {
  const Scale& scale = bench.scale();
  std::vector<std::string> buildings{scale.floorBuilding};
  for (const std::string& b : scale.buildings)
    if (b != scale.floorBuilding) buildings.push_back(b);
  Csv csv(concat({"building", "triangles", "cells", "photons", "resolution", "accel", "best"}, kMeasurementColumns));
  std::vector<std::string> header{"building"};
  for (int r : scale.gridResolutions) header.push_back(fmt::format("R={}", r));
  for (const char* h : {"best R", "best s", "embree s"}) header.push_back(h);
  std::vector<std::vector<std::string>> rows;
  PlotPanel floorPanel{fmt::format("Fig. 4: {} (one floor), grid resolution", scale.floorBuilding),
                       "grid resolution (voxels along the longest axis)", "photon pass s (builds included)",
                       false, false, {}};
  PlotPanel othersPanel{"Fig. 5: grid resolution per building", "grid resolution", "photon pass s", false, false, {}};
  nlohmann::json best = nlohmann::json::object();
  for (size_t b = 0; b < buildings.size(); ++b) {
    const std::string& building = buildings[b];
    const Store& store = bench.topological(building);
    const uint64_t photons = bench.photons(building, scale.photonsPerLight);
    const std::vector<SweepPoint> points = gridSweep(bench, building);
    const SweepPoint* winner = fastest(points);
    const Measurement& embree = bench.measure(store, "embree", photons);
    std::vector<std::string> row{building};
    PlotSeries series{building, kSeriesColors[b % 8], false, {}, {}, -1};
    for (size_t i = 0; i < points.size(); ++i) {
      const int r = scale.gridResolutions[i];
      row.push_back(formatSeconds(points[i].m->seconds()));
      series.x.push_back(r), series.y.push_back(points[i].m->seconds());
      if (&points[i] == winner) series.marked = int(i);
      csv.row(concat({building, std::to_string(store.triangles), std::to_string(store.cells), std::to_string(photons),
                      std::to_string(r), points[i].spec, &points[i] == winner ? "1" : "0"},
                     measurementCells(*points[i].m)));
    }
    csv.row(concat({building, std::to_string(store.triangles), std::to_string(store.cells), std::to_string(photons),
                    "", "embree", "0"},
                   measurementCells(embree)));
    const int bestR = winner ? scale.gridResolutions[size_t(winner - points.data())] : 0;
    row.push_back(winner ? std::to_string(bestR) : "n/a");
    row.push_back(formatSeconds(secondsOf(winner)));
    row.push_back(formatSeconds(embree.seconds()));
    rows.push_back(row);
    PlotSeries flat{"embree (" + building + ")", kSeriesColors[b % 8], true, {}, {}, -1};
    flat.x = {double(scale.gridResolutions.front()), double(scale.gridResolutions.back())};
    flat.y = {embree.seconds(), embree.seconds()};
    PlotPanel& panel = b == 0 ? floorPanel : othersPanel;
    panel.series.push_back(series);
    panel.series.push_back(flat);
    best[building] = {{"resolution", bestR}, {"seconds", secondsOf(winner)}, {"embree_seconds", embree.seconds()},
                      {"photons", photons}};
  }
  printTable(fmt::format("Figs. 4-5: photon pass (s, builds included) vs grid resolution; {}",
                         scaleNote(bench, scale.photonsPerLight)),
             header, rows, "paper: best R ~48 for hand-furnished (l-shape, octagon), ~96 for regular (z-building, tower)");
  csv.write(bench.out() / "fig4_5_grid_resolution.csv");
  std::vector<PlotPanel> panels{floorPanel};
  if (!othersPanel.series.empty()) panels.push_back(othersPanel);
  writePlotPng((bench.out() / "fig4_5_grid_resolution.png").string(), panels, 760, 480);
  bench.summary()["fig4_5_grid_resolution"] = {{"best_resolution", best}};
}

// ---------------------------------------------------------------------------
// Fig. 6: hierarchical grid initialisation time against the most triangles a
// voxel may hold before it is subdivided, with a fixed top resolution.

void experimentHgridInit(Bench& bench) {
  const Scale& scale = bench.scale();
  const std::string& building = scale.floorBuilding;
  const Store& store = bench.topological(building);
  const uint64_t photons = bench.photons(building, scale.photonsPerLight);
  Csv csv(concat({"building", "photons", "top_resolution", "max", "accel"}, kMeasurementColumns));
  std::vector<std::vector<std::string>> rows;
  PlotSeries build{"initialisation (builds, all workers)", kSeriesColors[1], false, {}, {}, -1};
  PlotSeries total{"photon pass (builds included)", kSeriesColors[0], true, {}, {}, -1};
  nlohmann::json points = nlohmann::json::array();
  for (int maxRefs : scale.hgridMax) {
    const std::string spec = fmt::format("hgrid:res={},max={}", scale.hgridResolution, maxRefs);
    const Measurement& m = bench.measure(store, spec, photons);
    rows.push_back({std::to_string(maxRefs), formatSeconds(m.buildSeconds()), formatSeconds(m.seconds())});
    build.x.push_back(maxRefs), build.y.push_back(m.buildSeconds());
    total.x.push_back(maxRefs), total.y.push_back(m.seconds());
    csv.row(concat({building, std::to_string(photons), std::to_string(scale.hgridResolution), std::to_string(maxRefs),
                    spec},
                   measurementCells(m)));
    points.push_back({{"max", maxRefs}, {"build_seconds", m.buildSeconds()}, {"seconds", m.seconds()}});
  }
  printTable(fmt::format("Fig. 6: hgrid:res={} on {}: initialisation vs max triangles per voxel; {}",
                         scale.hgridResolution, building, scaleNote(bench, scale.photonsPerLight)),
             {"max", "init s", "photon pass s"}, rows,
             "init s: the workers' accelerator builds added up (time_ms.accelerator_build); paper: init time falls "
             "as max grows");
  csv.write(bench.out() / "fig6_hgrid_init.csv");
  PlotPanel panel{fmt::format("Fig. 6: {}, hgrid top res {}", building, scale.hgridResolution),
                  "max triangles per voxel", "seconds", true, false, {build, total}};
  writePlotPng((bench.out() / "fig6_hgrid_init.png").string(), {panel}, 760, 480);
  // Does initialisation get cheaper as voxels may hold more (the paper's claim)?
  bool falls = true;
  for (size_t i = 1; i < build.y.size(); ++i) falls = falls && !(build.y[i] > build.y[i - 1] * 1.1);
  bench.summary()["fig6_hgrid_init"] = {{"building", building}, {"top_resolution", scale.hgridResolution},
                                        {"points", points}, {"init_falls_as_max_grows", falls}};
}

}  // namespace portico::cli::paper
