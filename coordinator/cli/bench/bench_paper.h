// `portico bench paper`: every experiment of Fradin & Meneveaux (2006) §6
// rerun through the real pipeline (docs/paper-benchmark.md).
#pragma once

#include <cstdint>
#include <string>

namespace portico::cli {

struct BenchPaperOptions {
  std::string out = "bench-paper";   // CSVs, PNGs, summary.json; generated stores under OUT/stores
  bool quick = false;                // a reduced version of every experiment (minutes)
  bool smoke = false;                // hidden: the smallest version (the ctest), l-shape only
  std::string buildings;             // comma-separated subset of the default buildings ("" = all of the mode's)
  std::string experiments;           // comma-separated subset of the experiments ("" = all)
  uint64_t photonsPerLight = 0;      // 0: the mode's default (quick 300, default 1000)
  uint32_t workers = 2;
  uint32_t runs = 1;                 // runs per measurement (median)
  uint64_t seed = 1;                 // the photon passes' seed
  uint64_t sceneSeed = 1;            // the generated buildings' furnishing seed
  std::string memory = "4GiB";       // per worker
  double timeoutSeconds = 0;         // per run; 0: the mode's default
};

int runBenchPaper(const BenchPaperOptions& options);

}  // namespace portico::cli
