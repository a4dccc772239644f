// The `portico` command's subcommands.
#pragma once

#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include <capnp/message.h>

#include "common/analysis/sensor.h"
#include "common/analysis/work_plane_grid.h"
#include "common/job/job_settings.h"
#include "common/scene/generator/panel_lighting.h"
#include "common/scene/import/building_importer.h"
#include "coordinator/cli/ifc_conversion.h"

namespace portico::cli {

// Options shared by `render` and `submit`: what the job computes, with the
// job's own defaults (common/job/job_settings.h).
void addRenderOptions(CLI::App& command, JobSettings& options);
// --falsecolor, --falsecolor-max, --falsecolor-log, --falsecolor-steps (each implies --aov luminance).
void addFalseColorOptions(CLI::App& command, JobSettings& options);
// Their daylight: --sun, --sun-time (and its place), --sky, --sun-irradiance,
// --turbidity (docs/daylight.md); also `scene export FILE.rad`'s sky.
void addDaylightOptions(CLI::App& command, DaylightSettings& daylight);
// Of those, the light and how it is computed (daylight, photons, samples,
// gather rays, seed, ...), which `analyze` takes too; `samplesHelp` says
// what --spp counts.
void addLightingOptions(CLI::App& command, JobSettings& options, const std::string& samplesHelp);
// The Submit message of a job (and its sensors, for an analysis); checks
// what the client can check before anything starts.
void fillSubmit(const JobSettings& settings, capnp::MallocMessageBuilder& message,
                const std::vector<Sensor>* sensors = nullptr);

int runSceneGenerate(const std::string& preset, uint64_t seed, uint32_t floors, const std::string& store,
                     const PanelLighting& panels = {});
// `scene import`: a building.json or mesh files -> store; prints the summary of `scene info`.
// An .ifc input goes through the IFC converter first, read as `ifc` says.
int runSceneImport(const std::vector<std::string>& inputs, const ImportOptions& options, const std::string& store,
                   const IfcOptions& ifc = {});
// `scene info`: counts (Tables 1 and 2 of the paper), bytes raw and
// compressed, and the validation pass; exit status 1 when the store is invalid.
struct SceneInfoOptions {
  bool json = false;
  bool compress = true;   // zlib every file for bytes_compressed: minutes on a store of GBs
  bool readCells = true;  // read every cell file (validateSceneStore); false: their sizes only
};
int runSceneInfo(const std::string& store, const SceneInfoOptions& options);
// The summary printed after generate and import: as above, without
// compressing or reading back the cell files just written (their sizes only).
int runSceneInfo(const std::string& store, bool json);
// `scene plan`: top-down floor plans as a PNG (scene_plan.h).
struct ScenePlanOptions {
  std::string output;
  int floor = -1;         // -1: every floor
  int panelSize = 800;    // pixels along the longer side of a floor's panel
};
int runScenePlan(const std::string& store, const ScenePlanOptions& options);
// `portico scene ies FILE...`: each photometric file's standard, grid and
// total lumens as portico reads it (docs/photometric-lights.md).
int runSceneIes(const std::vector<std::string>& files);

struct LocalRunOptions {
  uint32_t workers = 2;
  std::string memory = "2GiB";
  bool keepLogs = false;
  std::string logLevel = "info";
  std::string keys;   // CURVE keys for the local services ("" for none)
};
// sensors: an analysis job's (render.analysis), in their file's order.
int runRender(const JobSettings& render, const LocalRunOptions& local, const std::vector<Sensor>* sensors = nullptr);
// `analyze`: sensors from a .pts file (or a grid), measured by a job as a
// render is (analyze_command.cpp; docs/lighting-analysis.md).
struct AnalysisOptions {
  std::string sensorsFile;   // --sensors FILE.pts
  std::string grid;          // --grid auto
  WorkPlaneGridOptions gridOptions;        // --grid-height, --grid-spacing, ... (work_plane_grid_command.h)
  std::string thresholds = "100,300,500";  // analyze's --thresholds: lux of the per-room table (analysis_report.h)
  bool daylightFactor = false;
};
// The analysis's sensors, and `settings` made an analysis of them (its
// daylight the CIE overcast sky with --daylight-factor). Throws
// std::invalid_argument in one line naming the file and line, or the option.
std::vector<Sensor> prepareAnalysis(JobSettings& settings, const AnalysisOptions& analysis);
// Warns on stderr of the sensors outside every cell of the store (when the
// client can read it), naming their lines: they are not measured.
void warnOfSensorsOutsideCells(const std::string& store, const std::vector<Sensor>& sensors,
                               const std::string& sensorsFile);
int runAnalyze(JobSettings settings, const AnalysisOptions& analysis, const LocalRunOptions& local);
// `render --views FILE.json -o DIR/`: several views after one photon pass (views_command.cpp).
struct ViewsOptions {
  std::string file;            // the views file (view_list.h)
  std::string format = "exr";  // each image is DIR/<name>.<format>
};
int runViews(const JobSettings& base, const LocalRunOptions& local, const ViewsOptions& views);

// How the client commands reach a running coordinator.
struct ConnectOptions {
  std::string endpoint;
  std::string keys;             // CURVE keys directory ("" for none)
  double timeoutSeconds = 30;   // per request
};
void addConnectOptions(CLI::App& command, ConnectOptions& options);

// Where a submitted job stands in the queue: its priority (higher first)
// and the tags its workers must have (worker pools). Scheduling only: the
// job computes the same bits whatever they are.
struct Placement {
  int32_t priority = 0;
  std::vector<std::string> requiredTags;
};
int runSubmit(const ConnectOptions& connect, const JobSettings& render, const Placement& placement,
              const std::vector<Sensor>* sensors = nullptr);
int runStatus(const ConnectOptions& connect, uint64_t job, bool json);
int runWait(const ConnectOptions& connect, uint64_t job, bool quiet);
int runCancel(const ConnectOptions& connect, uint64_t job);
// `priority JOB N`: the job's leases from now on come in that priority's order.
int runPriority(const ConnectOptions& connect, uint64_t job, int32_t priority);
// `fetch-image JOB [-o FILE]`: the client writes the image (default: the job's output path).
int runFetchImage(const ConnectOptions& connect, uint64_t job, const std::string& output);
int runShutdown(const ConnectOptions& connect);

// `keys generate DIR`: a CURVE key pair for the coordinator and one per role (keys_command.cpp).
int runKeysGenerate(const std::string& directory);

// The subcommands, their options and their actions, by group: scene
// (scene_command_line.cpp), render and the job commands
// (job_command_line.cpp), keys (keys_command.cpp); bench is
// bench/bench_command_line.h's.
class CommandTable;
void addSceneCommands(CLI::App& app, CommandTable& table);
void addJobCommands(CLI::App& app, CommandTable& table);
void addKeysCommands(CLI::App& app, CommandTable& table);
// `dashboard` (dashboard/dashboard_command.cpp).
void addDashboardCommand(CLI::App& app, CommandTable& table);

}  // namespace portico::cli
