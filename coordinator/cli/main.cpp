// portico: the user's command. Generates and inspects scene stores, renders
// locally (its own coordinator and workers), and talks to running services.
#include <CLI/CLI.hpp>

#include <iostream>

#include "common/scene/building_importer.h"
#include "coordinator/cli/commands.h"

int main(int argc, char** argv) {
  using namespace portico::cli;
  CLI::App app{"portico: photon mapping for very large buildings, cell by cell"};
  app.require_subcommand(1);

  auto* scene = app.add_subcommand("scene", "create and inspect scene stores");
  scene->require_subcommand(1);
  std::string preset, store;
  uint64_t seed = 1;
  uint32_t floors = 1;
  auto* generate = scene->add_subcommand("generate", "generate a building into a scene store");
  generate->add_option("--preset", preset, "building preset: demo")->required();
  generate->add_option("--seed", seed, "random seed of the furnishing")->capture_default_str();
  generate->add_option("--floors", floors, "floors (presets that have several)")->capture_default_str();
  generate->add_option("STORE", store, "scene store directory to write")->required();
  std::vector<std::string> importInputs;
  portico::ImportOptions importOptions;
  auto* import = scene->add_subcommand("import", "import a building.json, or mesh files, into a scene store");
  import->add_option("--grid", importOptions.gridResolution,
                     "cut the scene into RGxRGxRG uniform voxel cells instead of its own cells (0: off)")
      ->capture_default_str()
      ->check(CLI::Range(0u, portico::kMaxImportGridResolution));
  import->add_option("--camera", importOptions.camera, "the building.json's camera of this name (default: the first)");
  import->add_option("INPUT", importInputs, "building.json, or mesh files (OBJ, PLY, glTF/GLB, ...)")
      ->required();
  import->add_option("STORE", store, "scene store directory to write")->required();
  import->positionals_at_end();   // INPUT... takes all but the last positional, STORE the last
  bool json = false;
  auto* info = scene->add_subcommand("info", "describe a scene store");
  info->add_option("STORE", store, "scene store directory")->required()->check(CLI::ExistingDirectory);
  info->add_flag("--json", json, "one JSON object on stdout");

  RenderOptions render;
  LocalRunOptions local;
  auto* renderCommand = app.add_subcommand("render", "render locally: starts a coordinator and workers");
  addRenderOptions(*renderCommand, render);
  renderCommand->add_option("--workers", local.workers, "local worker processes")->capture_default_str();
  renderCommand->add_option("--memory", local.memory, "cache budget per worker")->capture_default_str();
  renderCommand->add_flag("--keep-logs", local.keepLogs, "keep the services' logs and jobs.db");
  renderCommand->add_option("--log-level", local.logLevel, "services' log level")->capture_default_str();

  std::string endpoint;
  uint64_t job = 0;
  auto* submit = app.add_subcommand("submit", "submit a job to a running coordinator; prints its id");
  submit->add_option("--coordinator", endpoint, "coordinator endpoint")->required();
  addRenderOptions(*submit, render);
  auto* status = app.add_subcommand("status", "show a job's progress (or every job)");
  status->add_option("--coordinator", endpoint, "coordinator endpoint")->required();
  status->add_option("JOB", job, "job id");
  status->add_flag("--json", json, "one JSON object on stdout");
  bool quiet = false;
  auto* wait = app.add_subcommand("wait", "block until a job ends; exit 0 if it is done");
  wait->add_option("--coordinator", endpoint, "coordinator endpoint")->required();
  wait->add_option("JOB", job, "job id")->required();
  wait->add_flag("--quiet", quiet, "no progress lines");
  auto* cancel = app.add_subcommand("cancel", "cancel a job");
  cancel->add_option("--coordinator", endpoint, "coordinator endpoint")->required();
  cancel->add_option("JOB", job, "job id")->required();

  BenchAccelOptions benchAccel;
  auto* bench = app.add_subcommand("bench", "measure portico's parts");
  bench->require_subcommand(1);
  auto* benchAccelCommand =
      bench->add_subcommand("accel", "build time and tracing speed of the accelerators on furnished cells");
  benchAccelCommand->add_option("--sizes", benchAccel.sizes, "triangle counts of the cells (e.g. 1000,10k,1M)")
      ->capture_default_str();
  benchAccelCommand->add_option("--rays", benchAccel.rays, "rays per kind (photon, camera) and size")
      ->capture_default_str();
  benchAccelCommand
      ->add_option("--specs", benchAccel.specs,
                   "accelerator specs, comma-separated (name=value items belong to the spec before them; ';' "
                   "also separates); kinds not in this build are skipped")
      ->capture_default_str();
  benchAccelCommand->add_option("--csv", benchAccel.csv, "write one row per structure, size and ray kind");
  benchAccelCommand->add_option("--plot", benchAccel.plot, "write a PNG: build time and Mrays/s against triangles");
  benchAccelCommand->add_option("--seed", benchAccel.seed, "seed of the furnishing and of the rays")
      ->capture_default_str();
  benchAccelCommand->add_option("--runs", benchAccel.runs, "timed runs per measurement (the median is reported)")
      ->capture_default_str()
      ->check(CLI::Range(1u, 100u));
  benchAccelCommand
      ->add_option("--embree-threads", benchAccel.embreeThreads,
                   "threads of Embree's builder (0: every core); 1 compares like with like")
      ->capture_default_str();

  CLI11_PARSE(app, argc, argv);
  try {
    if (*generate) return runSceneGenerate(preset, seed, floors, store);
    if (*import) return runSceneImport(importInputs, importOptions, store);
    if (*info) return runSceneInfo(store, json);
    if (*renderCommand) return runRender(render, local);
    if (*submit) return runSubmit(endpoint, render);
    if (*status) return runStatus(endpoint, job, json);
    if (*wait) return runWait(endpoint, job, quiet);
    if (*cancel) return runCancel(endpoint, job);
    if (*benchAccelCommand) return runBenchAccel(benchAccel);
  } catch (const std::exception& e) {
    std::cerr << "portico: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
