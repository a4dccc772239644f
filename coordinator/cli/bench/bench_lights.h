// `portico bench lights STORE --camera NAME`: the render phase of one view
// with each way of choosing a light (--light-sampler scan, tree), in
// interleaved runs of `portico render` (bench pipeline's runner), each image
// scored with `portico-compare` against a converged reference of the same
// view and photons (rendered first with many samples per pixel, or given).
// Prints a table per run and the medians, and writes one CSV row per run.
#pragma once

#include <cstdint>
#include <string>

namespace portico::cli {

struct BenchLightsOptions {
  std::string store;
  std::string camera;              // a store camera (portico scene info lists them)
  std::string reference;           // an EXR of the view; empty: rendered here (kept with --keep-reference)
  std::string keepReference;       // where to keep the reference rendered here
  std::string referenceSampler = "scan";
  uint32_t referenceSpp = 256;
  uint64_t photons = 1000000;
  uint64_t seed = 1;
  uint32_t spp = 4, gather = 4, width = 320, height = 180;
  uint32_t treeSpp = 0;            // the tree's runs' spp; 0: spp (more, to compare at equal error)
  uint32_t workers = 2;
  std::string memory = "2GiB";
  std::string accel = "bvh";
  uint32_t runs = 3;               // per sampler, interleaved
  std::string csv;
};

int runBenchLights(const BenchLightsOptions& options);

}  // namespace portico::cli
