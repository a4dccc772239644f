// The `portico` command's subcommands.
#pragma once

#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "common/scene/building_importer.h"

namespace portico::cli {

// Options shared by `render` and `submit`: what the job computes.
struct RenderOptions {
  std::string store;
  std::string output;
  std::string accel = "grid";
  // Defaults checked against the reference scenes (docs/validation.md):
  // final gathering at every camera hit, N-rooks pixel samples.
  uint64_t photons = 200000;
  uint32_t spp = 16;
  uint32_t gather = 8;
  uint64_t seed = 1;
  uint32_t width = 0, height = 0;
  uint32_t lightSamples = 2;
  int lightHops = 2;
  uint32_t photonK = 64;
  float photonRadius = 0.5f;
  float exposure = 1.0f;
  std::string aov = "radiance";
};

void addRenderOptions(CLI::App& command, RenderOptions& options);

int runSceneGenerate(const std::string& preset, uint64_t seed, uint32_t floors, const std::string& store);
// `scene import`: a building.json or mesh files -> store; prints the summary of `scene info`.
int runSceneImport(const std::vector<std::string>& inputs, const ImportOptions& options, const std::string& store);
int runSceneInfo(const std::string& store, bool json);

struct LocalRunOptions {
  uint32_t workers = 2;
  std::string memory = "2GiB";
  bool keepLogs = false;
  std::string logLevel = "info";
};
int runRender(const RenderOptions& render, const LocalRunOptions& local);

// `bench accel`: accelerators on furnished cells of chosen sizes (bench_command.cpp).
struct BenchAccelOptions {
  std::string sizes = "1000,10000,100000,1000000";
  uint64_t rays = 100000;
  std::string specs = "grid,hgrid,kd:median,kd:sah,kd:bbox,embree";
  std::string csv;
  std::string plot;
  uint64_t seed = 1;
  uint32_t runs = 3;
  uint32_t embreeThreads = 1;  // 0: Embree's default (every core)
};
int runBenchAccel(const BenchAccelOptions& options);

int runSubmit(const std::string& endpoint, const RenderOptions& render);
int runStatus(const std::string& endpoint, uint64_t job, bool json);
int runWait(const std::string& endpoint, uint64_t job, bool quiet);
int runCancel(const std::string& endpoint, uint64_t job);

}  // namespace portico::cli
