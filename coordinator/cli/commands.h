// The `portico` command's subcommands.
#pragma once

#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "common/job/job_settings.h"
#include "common/scene/building_importer.h"

namespace portico::cli {

// Options shared by `render` and `submit`: what the job computes, with the
// job's own defaults (common/job/job_settings.h).
using RenderOptions = JobSettings;

void addRenderOptions(CLI::App& command, RenderOptions& options);

int runSceneGenerate(const std::string& preset, uint64_t seed, uint32_t floors, const std::string& store);
// `scene import`: a building.json or mesh files -> store; prints the summary of `scene info`.
// An .ifc input goes through the IFC converter first; ifcLights: auto, fixtures or panels.
int runSceneImport(const std::vector<std::string>& inputs, const ImportOptions& options, const std::string& store,
                   const std::string& ifcLights = "auto");
// `scene info`: counts (Tables 1 and 2 of the paper), bytes raw and
// compressed, and the validation pass; exit status 1 when the store is invalid.
struct SceneInfoOptions {
  bool json = false;
  bool compress = true;   // zlib every file for bytes_compressed: minutes on a store of GBs
};
int runSceneInfo(const std::string& store, const SceneInfoOptions& options);
// The summary printed after generate and import: as above, without compressing.
int runSceneInfo(const std::string& store, bool json);
// `scene plan`: top-down floor plans as a PNG (scene_plan.h).
struct ScenePlanOptions {
  std::string output;
  int floor = -1;         // -1: every floor
  int panelSize = 800;    // pixels along the longer side of a floor's panel
};
int runScenePlan(const std::string& store, const ScenePlanOptions& options);

struct LocalRunOptions {
  uint32_t workers = 2;
  std::string memory = "2GiB";
  bool keepLogs = false;
  std::string logLevel = "info";
  std::string keys;   // CURVE keys for the local services ("" for none)
};
int runRender(const RenderOptions& render, const LocalRunOptions& local);

// `bench accel`: accelerators on furnished cells of chosen sizes (bench_command.cpp).
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

// `bench pipeline`: one photon pass over a generated building, in-core with
// Embree on 2 threads and through portico with 1 and 2 workers (bench_pipeline.cpp).
struct BenchPipelineOptions {
  std::string preset;
  std::string store;        // reuse the scene store there, or generate it there (and keep it); "" = temporary
  uint32_t floors = 0;      // the tower's floors
  uint64_t sceneSeed = 1;   // furnishing seed of the generated building
  uint64_t photons = 0;     // 0: the paper's workload, kPaperPhotonsPerLight per light of the building
  uint64_t seed = 1;        // the photon pass's seed
  std::string modes = "embree-incore-2t,portico-1w,portico-2w";
  std::string accel = "grid";
  std::string memory = "8GiB";  // per portico worker
  uint32_t runs = 1;
  std::string csv;
  std::string plot;
};
int runBenchPipeline(const BenchPipelineOptions& options);

// How the client commands reach a running coordinator.
struct ConnectOptions {
  std::string endpoint;
  std::string keys;             // CURVE keys directory ("" for none)
  double timeoutSeconds = 30;   // per request
};
void addConnectOptions(CLI::App& command, ConnectOptions& options);

int runSubmit(const ConnectOptions& connect, const RenderOptions& render);
int runStatus(const ConnectOptions& connect, uint64_t job, bool json);
int runWait(const ConnectOptions& connect, uint64_t job, bool quiet);
int runCancel(const ConnectOptions& connect, uint64_t job);
// `fetch-image JOB [-o FILE]`: the client writes the image (default: the job's output path).
int runFetchImage(const ConnectOptions& connect, uint64_t job, const std::string& output);
int runShutdown(const ConnectOptions& connect);

// `keys generate DIR`: a CURVE key pair for the coordinator and one per role (keys_command.cpp).
int runKeysGenerate(const std::string& directory);

}  // namespace portico::cli
