// `portico bench pipeline`: one photon pass over a generated building, in-core
// with Embree on 2 threads and through portico with 1 and 2 workers
// (bench_pipeline.cpp).
#pragma once

#include <cstdint>
#include <string>

namespace portico::cli {

struct BenchPipelineOptions {
  std::string preset;
  std::string store;        // reuse the scene store there, or generate it there (and keep it); "" = temporary
  uint32_t floors = 0;      // the tower's floors
  uint64_t sceneSeed = 1;   // furnishing seed of the generated building
  uint64_t photons = 0;     // 0: the paper's workload, kPaperPhotonsPerLight per light of the building
  uint64_t seed = 1;        // the photon pass's seed
  std::string modes = "embree-incore-2t,portico-1w,portico-2w";
  std::string accel = "auto";   // portico's default (JobSettings::accel)
  std::string memory = "8GiB";  // per portico worker
  uint32_t runs = 1;
  std::string csv;
  std::string plot;
};

int runBenchPipeline(const BenchPipelineOptions& options);

}  // namespace portico::cli
