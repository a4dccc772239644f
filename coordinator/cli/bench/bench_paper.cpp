// `portico bench paper`: the experiments of Fradin & Meneveaux (2006) §6,
// each measurement a real `portico render` child process (coordinator and
// workers) over a generated building, timed by the job's own statistics
// (time_ms.photons: submission to the last photon Result, cell loads and
// accelerator builds included, as the paper's "cumulative time for
// initializing ... and propagating photons"). docs/paper-benchmark.md.
//
// This file is the runner: it picks the scale (paper_scale.h) and runs the
// experiments asked for (paper_experiments.h) in the paper's order, through
// one Bench (paper_bench.h), writing summary.json after each.
#include "coordinator/cli/bench/bench_paper.h"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "coordinator/cli/bench/paper_bench.h"
#include "coordinator/cli/bench/paper_experiments.h"
#include "coordinator/cli/bench/paper_scale.h"

namespace portico::cli {

using namespace paper;

namespace {

const std::vector<std::string> kExperiments{"fig4_5_grid_resolution", "fig6_hgrid_init",
                                            "table3_kd_depth",        "fig7_8_kd_heuristics",
                                            "fig9_best_topological",  "table4_uniform_cells",
                                            "fig11_topological_vs_uniform", "auto_vs_fixed"};

using Experiment = std::function<void(Bench&)>;

// By name, the names as --experiments takes them.
const std::map<std::string, Experiment>& experiments() {
  static const std::map<std::string, Experiment> table{
      {"fig4_5_grid_resolution", experimentGridResolution},
      {"fig6_hgrid_init", experimentHgridInit},
      {"table3_kd_depth", experimentKdDepth},
      {"fig7_8_kd_heuristics", experimentKdHeuristics},
      {"fig9_best_topological", experimentBestTopological},
      {"table4_uniform_cells", experimentUniformCells},
      {"fig11_topological_vs_uniform", experimentTopologicalVsUniform},
      {"auto_vs_fixed", experimentAutoVsFixed}};
  return table;
}

}  // namespace

int runBenchPaper(const BenchPaperOptions& options) {
  if (options.workers == 0) throw std::invalid_argument("--workers must be at least 1");
  const Scale scale = chooseScale(options);
  std::vector<std::string> chosen = options.experiments.empty() ? kExperiments : splitList(options.experiments);
  for (const std::string& name : chosen)
    if (!experiments().count(name))
      throw std::invalid_argument(
          fmt::format("--experiments: unknown '{}' (known: {})", name, fmt::join(kExperiments, ", ")));
  const auto start = Clock::now();
  Bench bench(options, scale);
  const std::string header = scaleHeader(options, scale);
  std::cout << header;
  std::cout.flush();
  {
    std::ofstream readme(bench.out() / "README.txt");
    readme << header;
  }
  bench.summary()["scale"] = scaleJson(options, scale);
  bench.summary()["paper"] = "Fradin & Meneveaux 2006, Acceleration schemes for ray tracing large buildings, section 6";
  for (const std::string& name : kExperiments) {   // the paper's order, whatever the order asked
    if (std::find(chosen.begin(), chosen.end(), name) == chosen.end()) continue;
    const auto experimentStart = Clock::now();
    experiments().at(name)(bench);
    bench.summary()["seconds"][name] = secondsSince(experimentStart);
    bench.writeSummary();   // after every experiment: an interrupted run keeps what it measured
    std::cout << fmt::format("wrote {}.csv and {}.png ({:.0f} s)\n", (bench.out() / name).string(), name,
                             secondsSince(experimentStart));
    std::cout.flush();
  }
  bench.summary()["seconds"]["total"] = secondsSince(start);
  bench.writeSummary();
  std::cout << fmt::format("\nportico bench paper: {} experiment(s) in {:.0f} s; wrote {}\n", chosen.size(),
                           secondsSince(start), (bench.out() / "summary.json").string());
  return 0;
}

}  // namespace portico::cli
