// The experiments of `portico bench paper`, one per figure or table of
// Fradin & Meneveaux 2006 §6 (docs/paper-benchmark.md). Each measures through
// the Bench's memo, prints its table, writes OUT/NAME.csv and OUT/NAME.png,
// and adds its findings to the summary under its name.
#pragma once

#include "coordinator/cli/bench/paper_bench.h"

namespace portico::cli::paper {

// paper_grid_experiments.cpp
void experimentGridResolution(Bench& bench);        // fig4_5_grid_resolution
void experimentHgridInit(Bench& bench);             // fig6_hgrid_init
// paper_kd_experiments.cpp
void experimentKdDepth(Bench& bench);               // table3_kd_depth
void experimentKdHeuristics(Bench& bench);          // fig7_8_kd_heuristics
// paper_cell_experiments.cpp
void experimentBestTopological(Bench& bench);       // fig9_best_topological
void experimentUniformCells(Bench& bench);          // table4_uniform_cells
void experimentTopologicalVsUniform(Bench& bench);  // fig11_topological_vs_uniform
// paper_auto_experiment.cpp
void experimentAutoVsFixed(Bench& bench);           // auto_vs_fixed

}  // namespace portico::cli::paper
