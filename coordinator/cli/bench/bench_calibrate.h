// `portico bench calibrate`: fits the `--accel auto` cost model to this
// machine (bench_calibrate.cpp).
#pragma once

#include <cstdint>
#include <string>

namespace portico::cli {

struct CalibrateOptions {
  std::string output;                 // "" = CostModel::defaultPath()
  std::string preset = "l-shape";     // building whose cells are measured
  std::string store;                  // or an existing scene store's cells
  size_t maxCells = 24;               // cells of the building, spread over its sizes
  std::string sizes = "3k,30k,300k";  // furnished halls
  uint64_t rays = 20000;              // photon-like rays per cell
  uint32_t runs = 2;                  // timed passes (median)
  uint64_t seed = 1;
  std::string csv;                    // every measurement beside the model's prediction
};

int runBenchCalibrate(const CalibrateOptions& options);

}  // namespace portico::cli
