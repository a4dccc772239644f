// `portico bench accel`: build time and tracing speed of the accelerators on
// furnished cells of chosen sizes (bench_accel.cpp).
#pragma once

#include <cstdint>
#include <string>

namespace portico::cli {

struct BenchAccelOptions {
  std::string sizes = "1000,10000,100000,1000000";
  uint64_t rays = 100000;
  std::string specs = "grid,hgrid,kd:median,kd:sah,kd:bbox,bvh,embree";
  std::string csv;
  std::string plot;
  uint64_t seed = 1;
  uint32_t runs = 3;
  uint32_t embreeThreads = 1;  // 0: Embree's default (every core)
};

int runBenchAccel(const BenchAccelOptions& options);

}  // namespace portico::cli
