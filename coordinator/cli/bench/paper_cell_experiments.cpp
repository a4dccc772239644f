// `portico bench paper`: the best structure per building with topological
// cells (Fig. 9), with uniform voxel cells (Table 4), and the two kinds of
// cells against each other (Fig. 11).
#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "coordinator/cli/bench/paper_experiments.h"
#include "coordinator/cli/bench/paper_output.h"

namespace portico::cli::paper {

// Fig. 9: the best of each structure with topological cells: the grid at
// its best resolution (Figs. 4-5), hgrid (defaults), the best kd heuristic
// (Fig. 8, many photons) and Embree.

namespace {

struct BestOfStructures {
  std::vector<std::pair<std::string, SweepPoint>> entries;   // structure -> its best (spec, measurement)
  std::optional<std::pair<std::string, SweepPoint>> winner;    // among portico's own (Embree apart)
};

// The fastest of portico's own structures: Embree is the baseline beside them.
void chooseWinner(BestOfStructures& best) {
  for (const auto& entry : best.entries)
    if (entry.first != "embree" && entry.second.m->ok() &&
        (!best.winner || entry.second.m->seconds() < best.winner->second.m->seconds()))
      best.winner = entry;
}

BestOfStructures bestTopological(Bench& bench, const std::string& building) {
  const Store& store = bench.topological(building);
  const uint64_t photons = bench.photons(building, bench.scale().photonsPerLight);
  BestOfStructures best;
  const auto add = [&](const std::string& structure, const SweepPoint* p) {
    if (p) best.entries.push_back({structure, *p});
  };
  const std::vector<SweepPoint> grids = gridSweep(bench, building);
  const std::vector<SweepPoint> kds = kdSweep(bench, store, photons);
  const SweepPoint hgrid{"hgrid", &bench.measure(store, "hgrid", photons)};
  const SweepPoint embree{"embree", &bench.measure(store, "embree", photons)};
  add("grid", fastest(grids));
  add("hgrid", &hgrid);
  add("kd", fastest(kds));
  add("embree", &embree);
  chooseWinner(best);
  return best;
}

double entrySeconds(const BestOfStructures& best, const std::string& structure) {
  for (const auto& [name, point] : best.entries)
    if (name == structure) return point.m->seconds();
  return kNaN;
}

std::string entrySpec(const BestOfStructures& best, const std::string& structure) {
  for (const auto& [name, point] : best.entries)
    if (name == structure) return point.spec;
  return "n/a";
}

}  // namespace

void experimentBestTopological(Bench& bench) {
  const Scale& scale = bench.scale();
  const std::vector<std::string> buildings = comparedBuildings(scale);
  const std::vector<std::string> structures{"grid", "hgrid", "kd", "embree"};
  Csv csv(concat({"building", "photons", "structure", "accel", "winner"}, kMeasurementColumns));
  std::vector<std::vector<std::string>> rows;
  BarPanel panel{fmt::format("Fig. 9: best per structure, topological cells, {}",
                             scaleNote(bench, scale.photonsPerLight)),
                 "photon pass s", {}, {}};
  for (const std::string& s : structures) panel.legend.push_back({s == "kd" ? "kd (best)" : s, structureColor(s)});
  nlohmann::json summary = nlohmann::json::object();
  size_t gridWins = 0;
  for (const std::string& building : buildings) {
    const BestOfStructures best = bestTopological(bench, building);
    const uint64_t photons = bench.photons(building, scale.photonsPerLight);
    std::vector<std::string> row{building};
    BarGroup group{building, "", {}};
    for (const std::string& structure : structures) {
      row.push_back(fmt::format("{} {}", formatSeconds(entrySeconds(best, structure)), entrySpec(best, structure)));
      group.bars.push_back(timeBar(structure == "kd" ? "kd" : structure, entrySeconds(best, structure)));
    }
    for (const auto& [structure, point] : best.entries)
      csv.row(concat({building, std::to_string(photons), structure, point.spec,
                      best.winner && best.winner->second.spec == point.spec ? "1" : "0"},
                     measurementCells(*point.m)));
    const std::string winner = best.winner ? best.winner->second.spec : "n/a";
    gridWins += best.winner && best.winner->first == "grid";
    const double bestSeconds = best.winner ? best.winner->second.m->seconds() : kNaN;
    row.push_back(winner);
    row.push_back(formatRatio(entrySeconds(best, "embree") / bestSeconds));
    rows.push_back(row);
    panel.groups.push_back(group);
    summary[building] = {{"winner", winner},
                         {"seconds", bestSeconds},
                         {"grid", entrySeconds(best, "grid")},
                         {"grid_spec", entrySpec(best, "grid")},
                         {"hgrid", entrySeconds(best, "hgrid")},
                         {"kd", entrySeconds(best, "kd")},
                         {"kd_spec", entrySpec(best, "kd")},
                         {"embree", entrySeconds(best, "embree")},
                         {"embree_over_best_portico", entrySeconds(best, "embree") / bestSeconds}};
  }
  printTable("Fig. 9: best photon pass (s) per structure, topological cells",
             {"building", "grid (best R)", "hgrid", "kd (best)", "embree", "winner (portico's)", "embree/winner"}, rows,
             "paper: with topological cells a regular grid is always fastest overall");
  csv.write(bench.out() / "fig9_best_topological.csv");
  writeBarPlotPng((bench.out() / "fig9_best_topological.png").string(), {panel}, 260 + 150 * int(buildings.size()),
                  480);
  bench.summary()["fig9_best_topological"] = {
      {"per_building", summary}, {"grid_wins_in", gridWins}, {"buildings", buildings.size()}};
}

// ---------------------------------------------------------------------------
// Table 4: uniform (voxel) cells: the building re-cut into RG^3 cells, the
// best time per structure (grid: automatic or 16 voxels along the longest
// axis; hgrid defaults; kd: best heuristic; Embree).

namespace {

struct UniformResult {
  const Store* store = nullptr;
  BestOfStructures best;
  std::vector<SweepPoint> kds;
};

UniformResult bestUniform(Bench& bench, const std::string& building, uint32_t grid) {
  UniformResult result;
  const Store& store = bench.uniform(building, grid);
  result.store = &store;
  const uint64_t photons = bench.photons(building, bench.scale().photonsPerLight);
  std::vector<SweepPoint> grids;
  for (const char* spec : {"grid", "grid:res=16"}) grids.push_back({spec, &bench.measure(store, spec, photons)});
  result.kds = kdSweep(bench, store, photons);
  const SweepPoint hgrid{"hgrid", &bench.measure(store, "hgrid", photons)};
  const SweepPoint embree{"embree", &bench.measure(store, "embree", photons)};
  BestOfStructures& best = result.best;
  if (const SweepPoint* p = fastest(grids)) best.entries.push_back({"grid", *p});
  best.entries.push_back({"hgrid", hgrid});
  if (const SweepPoint* p = fastest(result.kds)) best.entries.push_back({"kd", *p});
  best.entries.push_back({"embree", embree});
  chooseWinner(best);
  return result;
}

}  // namespace

void experimentUniformCells(Bench& bench) {
  const Scale& scale = bench.scale();
  const std::map<std::string, std::string> paper{{"l-shape", "RG 10 / 300 cells, 1159 tri: grid 113, hgrid 210, kd 46"},
                                                 {"octagon", "RG 16 / 768, 7206 tri: 935, 1101, 593"},
                                                 {"soda-hall", "RG 16 / 1760, 978 tri: 1575, 2760, 928"}};
  Csv csv(concat({"building", "rg", "cells", "non_empty_cells", "avg_triangles_per_cell", "avg_triangles_per_non_empty",
                  "photons", "structure", "accel", "winner"},
                 kMeasurementColumns));
  std::vector<std::vector<std::string>> rows;
  BarPanel panel{fmt::format("Table 4: uniform cells, {}", scaleNote(bench, scale.photonsPerLight)),
                 "photon pass s", {}, {}};
  for (const std::string s : {"grid", "hgrid", "kd", "embree"})
    panel.legend.push_back({s == "kd" ? "kd (best)" : s, structureColor(s)});
  nlohmann::json summary = nlohmann::json::object();
  for (const auto& [building, grids] : scale.uniformGrids) {
    for (uint32_t rg : grids) {
      const UniformResult r = bestUniform(bench, building, rg);
      const Store& store = *r.store;
      const uint64_t photons = bench.photons(building, scale.photonsPerLight);
      const double avg = double(store.triangles) / double(std::max<size_t>(1, store.cells));
      const double avgNonEmpty = double(store.triangles) / double(std::max<size_t>(1, store.nonEmptyCells));
      const std::vector<std::string> storeCells{building,
                                                std::to_string(rg),
                                                std::to_string(store.cells),
                                                std::to_string(store.nonEmptyCells),
                                                fmt::format("{:.1f}", avg),
                                                fmt::format("{:.1f}", avgNonEmpty),
                                                std::to_string(photons)};
      std::vector<const SweepPoint*> all;
      for (const auto& entry : r.best.entries) all.push_back(&entry.second);
      for (const SweepPoint& p : r.kds) all.push_back(&p);
      std::set<std::string> written;
      for (const auto& [structure, point] : r.best.entries) {
        written.insert(point.spec);
        csv.row(concat(concat(storeCells, {structure, point.spec,
                                           r.best.winner && r.best.winner->second.spec == point.spec ? "1" : "0"}),
                       measurementCells(*point.m)));
      }
      for (const SweepPoint& p : r.kds)   // the other heuristics too: which suits voxel cells (paper: bbox)
        if (!written.count(p.spec))
          csv.row(concat(concat(storeCells, {"kd", p.spec, "0"}), measurementCells(*p.m)));
      const std::string winner = r.best.winner ? r.best.winner->second.spec : "n/a";
      rows.push_back({building, std::to_string(rg),
                      fmt::format("{} ({} non-empty)", store.cells, store.nonEmptyCells), fmt::format("{:.0f}", avg),
                      fmt::format("{} {}", formatSeconds(entrySeconds(r.best, "grid")), entrySpec(r.best, "grid")),
                      formatSeconds(entrySeconds(r.best, "hgrid")),
                      fmt::format("{} {}", formatSeconds(entrySeconds(r.best, "kd")), entrySpec(r.best, "kd")),
                      formatSeconds(entrySeconds(r.best, "embree")), winner});
      BarGroup group{fmt::format("{} RG{}", building, rg), fmt::format("{} cells", store.cells), {}};
      for (const std::string s : {"grid", "hgrid", "kd", "embree"})
        group.bars.push_back(timeBar(s, entrySeconds(r.best, s)));
      panel.groups.push_back(group);
      summary[fmt::format("{} RG{}", building, rg)] = {
          {"building", building},       {"rg", rg},
          {"cells", store.cells},       {"non_empty_cells", store.nonEmptyCells},
          {"avg_triangles_per_cell", avg}, {"winner", winner},
          {"seconds", r.best.winner ? r.best.winner->second.m->seconds() : kNaN},
          {"grid", entrySeconds(r.best, "grid")}, {"hgrid", entrySeconds(r.best, "hgrid")},
          {"kd", entrySeconds(r.best, "kd")},   {"kd_spec", entrySpec(r.best, "kd")},
          {"embree", entrySeconds(r.best, "embree")}};
    }
  }
  std::string paperNote = "paper (s, 2006): ";
  for (const auto& [building, text] : paper)
    if (scale.uniformGrids.count(building)) paperNote += building + " " + text + "; ";
  printTable("Table 4: uniform cells: best photon pass (s) per structure",
             {"building", "RG", "cells", "avg tri/cell", "grid", "hgrid", "kd (best)", "embree", "winner"}, rows,
             paperNote + "paper: kd (bbox) fastest with uniform cells");
  csv.write(bench.out() / "table4_uniform_cells.csv");
  writeBarPlotPng((bench.out() / "table4_uniform_cells.png").string(), {panel},
                  260 + 150 * std::max<int>(1, int(panel.groups.size())), 480);
  bench.summary()["table4_uniform_cells"] = summary;
}

// ---------------------------------------------------------------------------
// Fig. 11: the best photon pass with topological cells against the best with
// uniform cells, and a real render (camera rays, final gathering) of both:
// its time and the share of its rays that cross a portal.

void experimentTopologicalVsUniform(Bench& bench) {
  const Scale& scale = bench.scale();
  Csv csv(concat({"building", "cells_kind", "rg", "cells", "photons", "kind", "accel"}, kMeasurementColumns));
  std::vector<std::vector<std::string>> rows;
  BarPanel photonPanel{"Fig. 11: best photon pass, topological vs uniform cells", "photon pass s", {}, {}};
  BarPanel renderPanel{fmt::format("render {}x{}, 1 spp, gather {}, {}", scale.renderWidth, scale.renderHeight,
                                   scale.renderGather, scale.renderAccel),
                       "render s", {}, {}};
  const Rgb topoColor{31, 119, 180}, uniformColor{255, 127, 14};
  for (BarPanel* p : {&photonPanel, &renderPanel})
    p->legend = {{"topological", topoColor}, {"uniform", uniformColor}};
  nlohmann::json summary = nlohmann::json::object();
  for (const auto& [building, grids] : scale.uniformGrids) {
    const BestOfStructures topo = bestTopological(bench, building);
    // The uniform cut with the fastest photon pass.
    std::optional<UniformResult> uniformBest;
    for (uint32_t rg : grids) {
      UniformResult r = bestUniform(bench, building, rg);
      if (r.best.winner && (!uniformBest || !uniformBest->best.winner ||
                            r.best.winner->second.m->seconds() < uniformBest->best.winner->second.m->seconds()))
        uniformBest = std::move(r);
    }
    if (!uniformBest) continue;
    const double topoSeconds = topo.winner ? topo.winner->second.m->seconds() : kNaN;
    const double uniformSeconds = uniformBest->best.winner ? uniformBest->best.winner->second.m->seconds() : kNaN;
    // The render: same photons per light, camera rays with final gathering.
    const RenderSetting render{1, scale.renderGather, scale.renderWidth, scale.renderHeight};
    const uint64_t photons = bench.photons(building, scale.fewPhotonsPerLight);
    const Store& topoStore = bench.topological(building);
    const Store& uniformStore = *uniformBest->store;
    const Measurement& topoRender = bench.measure(topoStore, scale.renderAccel, photons, render);
    const Measurement& uniformRender = bench.measure(uniformStore, scale.renderAccel, photons, render);
    const auto portalShare = [](const Measurement& m) {
      if (!m.ok()) return kNaN;
      const PipelineRunStats& s = m.typical();
      const int64_t started = s.cameraRays + s.shadowRays + s.gatherRays;
      return started > 0 ? double(s.rayCrossings) / double(started) : kNaN;
    };
    const auto tracedShare = [](const Measurement& m) {
      return m.ok() && m.typical().raysTraced > 0 ? double(m.typical().rayCrossings) / double(m.typical().raysTraced)
                                                  : kNaN;
    };
    const double renderRatio = uniformRender.renderSeconds() / topoRender.renderSeconds();
    rows.push_back({building, formatSeconds(topoSeconds) + " " + (topo.winner ? topo.winner->second.spec : ""),
                    fmt::format("{} {} RG{}", formatSeconds(uniformSeconds),
                                uniformBest->best.winner ? uniformBest->best.winner->second.spec : "",
                                uniformStore.grid),
                    formatRatio(uniformSeconds / topoSeconds), formatSeconds(topoRender.renderSeconds()),
                    formatSeconds(uniformRender.renderSeconds()), formatRatio(renderRatio),
                    fmt::format("{:.3f}", portalShare(topoRender)), fmt::format("{:.3f}", portalShare(uniformRender))});
    const auto csvRow = [&](const Store& store, const char* kind, const std::string& accel, const Measurement& m) {
      csv.row(concat({building, store.grid ? "uniform" : "topological", std::to_string(store.grid),
                      std::to_string(store.cells), std::to_string(m.photons), kind, accel},
                     measurementCells(m)));
    };
    if (topo.winner) csvRow(topoStore, "photon_pass_best", topo.winner->second.spec, *topo.winner->second.m);
    if (uniformBest->best.winner)
      csvRow(uniformStore, "photon_pass_best", uniformBest->best.winner->second.spec,
             *uniformBest->best.winner->second.m);
    csvRow(topoStore, "render", scale.renderAccel, topoRender);
    csvRow(uniformStore, "render", scale.renderAccel, uniformRender);
    photonPanel.groups.push_back({building, fmt::format("x{:.2f}", uniformSeconds / topoSeconds),
                                  {Bar{topoSeconds, topoColor, formatSeconds(topoSeconds), ""},
                                   Bar{uniformSeconds, uniformColor, formatSeconds(uniformSeconds), ""}}});
    renderPanel.groups.push_back(
        {building, fmt::format("x{:.2f}", renderRatio),
         {Bar{topoRender.renderSeconds(), topoColor, formatSeconds(topoRender.renderSeconds()),
              fmt::format("{:.3f}/ray", portalShare(topoRender))},
          Bar{uniformRender.renderSeconds(), uniformColor, formatSeconds(uniformRender.renderSeconds()),
              fmt::format("{:.3f}/ray", portalShare(uniformRender))}}});
    summary[building] = {{"photon_pass_topological", topoSeconds},
                         {"photon_pass_uniform", uniformSeconds},
                         {"uniform_rg", uniformStore.grid},
                         {"photon_pass_ratio_uniform_over_topological", uniformSeconds / topoSeconds},
                         {"render_topological", topoRender.renderSeconds()},
                         {"render_uniform", uniformRender.renderSeconds()},
                         {"render_ratio_uniform_over_topological", renderRatio},
                         {"portal_crossings_per_render_ray_topological", portalShare(topoRender)},
                         {"portal_crossings_per_render_ray_uniform", portalShare(uniformRender)},
                         {"ray_crossings_over_rays_traced_topological", tracedShare(topoRender)},
                         {"ray_crossings_over_rays_traced_uniform", tracedShare(uniformRender)}};
  }
  printTable("Fig. 11: topological vs uniform cells: best photon pass (s) and a render (s)",
             {"building", "topological best", "uniform best", "uni/topo", "render topo", "render uni", "uni/topo",
              "crossings/ray topo", "crossings/ray uni"},
             rows,
             fmt::format("render: {}x{}, 1 spp, final gather {} rays, --accel {}, {} photons/light; crossings/ray: "
                         "portal crossings of render rays per render ray started (camera + shadow + gather). paper: "
                         "rendering >= 4x faster with topological cells, < 5 % of rays hit portals",
                         scale.renderWidth, scale.renderHeight, scale.renderGather, scale.renderAccel,
                         scale.fewPhotonsPerLight));
  csv.write(bench.out() / "fig11_topological_vs_uniform.csv");
  const int groups = std::max<int>(1, int(photonPanel.groups.size()));
  writeBarPlotPng((bench.out() / "fig11_topological_vs_uniform.png").string(), {photonPanel, renderPanel},
                  300 + 150 * groups, 480);
  bench.summary()["fig11_topological_vs_uniform"] = summary;
}


}  // namespace portico::cli::paper
