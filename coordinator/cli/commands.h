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
  uint64_t photons = 500000;
  uint32_t spp = 16;
  uint32_t gather = 0;
  uint64_t seed = 1;
  uint32_t width = 0, height = 0;
  uint32_t lightSamples = 2;
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

int runSubmit(const std::string& endpoint, const RenderOptions& render);
int runStatus(const std::string& endpoint, uint64_t job, bool json);
int runWait(const std::string& endpoint, uint64_t job, bool quiet);
int runCancel(const std::string& endpoint, uint64_t job);

}  // namespace portico::cli
