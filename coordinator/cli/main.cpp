// portico: the user's command. Generates and inspects scene stores, renders
// locally (its own coordinator and workers), and talks to running services.
#include <CLI/CLI.hpp>

#include <iostream>

#include "common/scene/building_importer.h"
#include "coordinator/cli/bench_calibrate.h"
#include "coordinator/cli/bench_paper.h"
#include "coordinator/cli/bench_quality.h"
#include "coordinator/cli/commands.h"
#include "common/util/cli_bounds.h"
#include "coordinator/cli/scene_export.h"

int main(int argc, char** argv) {
  using namespace portico::cli;
  CLI::App app{"portico: photon mapping for very large buildings, cell by cell"};
  app.require_subcommand(1);

  auto* scene = app.add_subcommand("scene", "create and inspect scene stores");
  scene->require_subcommand(1);
  std::string preset, store;
  uint64_t seed = 1;
  uint32_t floors = 0;
  auto* generate = scene->add_subcommand("generate", "generate a building into a scene store");
  generate->add_option("--preset", preset, "building preset: demo, l-shape, z-building, octagon, soda-hall, tower")->required();
  generate->add_option("--seed", seed, "random seed of the furnishing")->capture_default_str();
  generate->add_option("--floors", floors, "floors of the tower preset (default 1); the other presets have their own");
  generate->add_option("STORE", store, "scene store directory to write")->required();
  std::vector<std::string> importInputs;
  portico::ImportOptions importOptions;
  auto* import = scene->add_subcommand("import", "import a building.json, or mesh files, into a scene store");
  import->add_option("--grid", importOptions.gridResolution,
                     "cut the scene into RGxRGxRG uniform voxel cells instead of its own cells (0: off)")
      ->capture_default_str()
      ->check(CLI::Range(0u, portico::kMaxImportGridResolution));
  import->add_option("--camera", importOptions.camera, "the building.json's camera of this name (default: the first)");
  std::string ifcLights = "auto";
  import->add_option("--lights", ifcLights,
                     "IFC input: lamps from the model's light fixtures (fixtures), one ceiling panel per space (panels), "
                     "or fixtures where the model has some, else panels (auto)")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "fixtures", "panels"}));
  import->add_option("INPUT", importInputs, "building.json, an IFC model (.ifc), or mesh files (OBJ, PLY, glTF/GLB, ...)")
      ->required();
  import->add_option("STORE", store, "scene store directory to write")->required();
  import->positionals_at_end();   // INPUT... takes all but the last positional, STORE the last
  bool json = false;
  auto* info = scene->add_subcommand("info", "describe a scene store");
  info->add_option("STORE", store, "scene store directory")->required()->check(CLI::ExistingDirectory);
  info->add_flag("--json", json, "one JSON object on stdout");
  bool noCompress = false;
  info->add_flag("--no-compress", noCompress, "skip the zlib-compressed size (slow on large stores)");
  std::string exportOutput;
  auto* exportCommand = scene->add_subcommand("export", "write a scene store as glTF (.glb, .gltf) or OBJ + MTL");
  exportCommand->add_option("STORE", store, "scene store directory")->required()->check(CLI::ExistingDirectory);
  exportCommand
      ->add_option("-o,--output", exportOutput,
                   "file to write: FILE.glb, FILE.gltf (FILE.bin beside it) or FILE.obj (FILE.mtl beside it)")
      ->required();
  ScenePlanOptions planOptions;
  auto* plan = scene->add_subcommand("plan", "draw top-down floor plans of a scene store as a PNG");
  plan->add_option("STORE", store, "scene store directory")->required()->check(CLI::ExistingDirectory);
  plan->add_option("-o,--output", planOptions.output, "PNG file to write")->required();
  plan->add_option("--floor", planOptions.floor, "draw only this floor (0 = lowest)")->check(CLI::NonNegativeNumber);
  plan->add_option("--size", planOptions.panelSize, "pixels along the longer side of each floor's panel")
      ->capture_default_str()
      ->check(CLI::Range(64, 8192));

  RenderOptions render;
  LocalRunOptions local;
  auto* renderCommand = app.add_subcommand("render", "render locally: starts a coordinator and workers");
  addRenderOptions(*renderCommand, render);
  renderCommand->add_option("--workers", local.workers, "local worker processes")
      ->capture_default_str()
      ->check(wholeNumber(1, 256));
  renderCommand->add_option("--memory", local.memory, "cache budget per worker")->capture_default_str()->check(byteSize());
  renderCommand->add_flag("--keep-logs", local.keepLogs, "keep the services' logs and jobs.db");
  renderCommand->add_option("--log-level", local.logLevel, "services' log level")->capture_default_str();
  renderCommand->add_option("--keys", local.keys, "CURVE keys directory for the local services (`portico keys generate`)")
      ->check(CLI::ExistingDirectory);

  ConnectOptions connect;
  uint64_t job = 0;
  auto* submit = app.add_subcommand("submit", "submit a job to a running coordinator; prints its id");
  addConnectOptions(*submit, connect);
  addRenderOptions(*submit, render);
  auto* status = app.add_subcommand("status", "show a job's progress (or every job)");
  addConnectOptions(*status, connect);
  status->add_option("JOB", job, "job id");
  status->add_flag("--json", json, "one JSON object on stdout");
  bool quiet = false;
  auto* wait = app.add_subcommand("wait", "block until a job ends; exit 0 if it is done");
  addConnectOptions(*wait, connect);
  wait->add_option("JOB", job, "job id")->required();
  wait->add_flag("--quiet", quiet, "no progress lines");
  auto* cancel = app.add_subcommand("cancel", "cancel a job");
  addConnectOptions(*cancel, connect);
  cancel->add_option("JOB", job, "job id")->required();
  std::string imagePath;
  auto* fetchImage = app.add_subcommand(
      "fetch-image", "write a done job's image (and its .json statistics) as this user, e.g. where the coordinator could not");
  addConnectOptions(*fetchImage, connect);
  fetchImage->add_option("JOB", job, "job id")->required();
  fetchImage->add_option("-o,--output", imagePath, "where to write it (default: the job's own output path)");
  auto* shutdown = app.add_subcommand("shutdown", "stop a running coordinator (needs the operator key: --keys DIR "
                                                  "with operator.secret, or its own user on ipc://)");
  addConnectOptions(*shutdown, connect);

  std::string keysDirectory;
  auto* keys = app.add_subcommand("keys", "ZeroMQ CURVE keys for services listening beyond loopback");
  keys->require_subcommand(1);
  auto* keysGenerate = keys->add_subcommand(
      "generate", "write the key pairs DIR lacks: coordinator, client, worker and operator .{public,secret} (Z85; "
                  "secrets mode 0600; existing keys are kept)");
  keysGenerate->add_option("DIR", keysDirectory, "directory to write the key files into")->required();

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

  BenchQualityOptions benchQuality;
  auto* benchQualityCommand = bench->add_subcommand(
      "quality", "error against time on a reference scene: a ladder of render settings (docs/image-quality.md)");
  benchQualityCommand->add_option("SCENE_DIR", benchQuality.sceneDirectory, "folder of scene.json and reference.exr")
      ->required()
      ->check(CLI::ExistingDirectory);
  benchQualityCommand->add_option("--settings", benchQuality.settings,
                                  "portico render arguments per rung, rungs separated by ';'")
      ->capture_default_str();
  benchQualityCommand->add_option("--workers", benchQuality.workers, "workers of each render")->capture_default_str();
  benchQualityCommand->add_option("--csv", benchQuality.csv, "write one row per setting");
  benchQualityCommand->add_option("--plot", benchQuality.plot, "write a PNG: block RMSE and worst block against seconds");

  BenchPipelineOptions benchPipeline;
  auto* benchPipelineCommand = bench->add_subcommand(
      "pipeline", "one photon pass over a generated building: in-core Embree (2 threads) vs portico (1, 2 workers)");
  benchPipelineCommand->add_option("--preset", benchPipeline.preset, "building preset: l-shape, z-building, octagon, soda-hall, tower")
      ->required();
  benchPipelineCommand->add_option("--photons", benchPipeline.photons,
                                   "photons of the pass (default: the paper's workload, 50 000 per light, at most 10 M: "
                                   "7.75 M for the octagon, 1.2 M for the l-shape)");
  benchPipelineCommand->add_option("--store", benchPipeline.store,
                                   "scene store to reuse, or to generate the building into and keep (default: a temporary one)");
  benchPipelineCommand->add_option("--floors", benchPipeline.floors, "floors of the tower preset");
  benchPipelineCommand->add_option("--scene-seed", benchPipeline.sceneSeed, "furnishing seed of the building")
      ->capture_default_str();
  benchPipelineCommand->add_option("--seed", benchPipeline.seed, "seed of the photon pass")->capture_default_str();
  benchPipelineCommand->add_option("--modes", benchPipeline.modes, "modes, comma-separated (portico-Nw for any N)")
      ->capture_default_str();
  benchPipelineCommand->add_option("--accel", benchPipeline.accel, "portico's accelerator spec")->capture_default_str();
  benchPipelineCommand->add_option("--memory", benchPipeline.memory, "cache budget per portico worker")
      ->capture_default_str();
  benchPipelineCommand->add_option("--runs", benchPipeline.runs, "runs per mode, interleaved (the median is reported)")
      ->capture_default_str()
      ->check(CLI::Range(1u, 100u));
  benchPipelineCommand->add_option("--csv", benchPipeline.csv, "write one row per mode");
  benchPipelineCommand->add_option("--plot", benchPipeline.plot, "write a PNG bar chart of photons/s");

  BenchPaperOptions benchPaper;
  auto* benchPaperCommand = bench->add_subcommand(
      "paper", "rerun every experiment of Fradin & Meneveaux 2006 section 6 through the pipeline (docs/paper-benchmark.md)");
  benchPaperCommand->add_flag("--quick", benchPaper.quick, "a reduced version of every experiment (a few minutes)");
  benchPaperCommand->add_flag("--smoke", benchPaper.smoke, "the smallest version, l-shape only (the ctest)")
      ->group("");   // hidden
  benchPaperCommand->add_option("--out", benchPaper.out, "directory of the CSVs, PNGs, summary.json and stores/")
      ->capture_default_str();
  benchPaperCommand->add_option("--buildings", benchPaper.buildings,
                                "buildings, comma-separated (l-shape, z-building, octagon, soda-hall, tower); "
                                "default: the mode's");
  benchPaperCommand->add_option("--experiments", benchPaper.experiments,
                                "experiments, comma-separated (default: all; fig4_5_grid_resolution, fig6_hgrid_init, "
                                "table3_kd_depth, fig7_8_kd_heuristics, fig9_best_topological, table4_uniform_cells, "
                                "fig11_topological_vs_uniform, auto_vs_fixed)");
  benchPaperCommand->add_option("--photons-per-light", benchPaper.photonsPerLight,
                                "photons per light of the passes (default: quick 300, otherwise 1000; the 'few' "
                                "count is 2/5 of it)");
  benchPaperCommand->add_option("--workers", benchPaper.workers, "workers of each render")->capture_default_str();
  benchPaperCommand->add_option("--runs", benchPaper.runs, "runs per measurement (the median is reported)")
      ->capture_default_str()
      ->check(CLI::Range(1u, 100u));
  benchPaperCommand->add_option("--seed", benchPaper.seed, "seed of the photon passes")->capture_default_str();
  benchPaperCommand->add_option("--scene-seed", benchPaper.sceneSeed, "furnishing seed of the buildings")
      ->capture_default_str();
  benchPaperCommand->add_option("--memory", benchPaper.memory, "cache budget per worker")->capture_default_str();
  benchPaperCommand->add_option("--timeout", benchPaper.timeoutSeconds,
                                "seconds a run may take before it is stopped and marked failed (default: the mode's)");

  CalibrateOptions calibrate;
  auto* calibrateCommand = bench->add_subcommand(
      "calibrate", "fit the --accel auto cost model to this machine and store it where workers look");
  calibrateCommand->add_option("-o,--out", calibrate.output,
                               "calibration file (default: $PORTICO_CALIBRATION, else ~/.cache/portico/calibration.json)");
  calibrateCommand->add_option("--preset", calibrate.preset, "building whose cells are measured")->capture_default_str();
  calibrateCommand->add_option("--store", calibrate.store, "measure this scene store's cells instead");
  calibrateCommand->add_option("--max-cells", calibrate.maxCells, "cells of the building, spread over its sizes")
      ->capture_default_str();
  calibrateCommand->add_option("--sizes", calibrate.sizes, "triangle counts of the furnished halls also measured")
      ->capture_default_str();
  calibrateCommand->add_option("--rays", calibrate.rays, "photon-like rays per cell")->capture_default_str()
      ->check(CLI::Range(uint64_t(100), uint64_t(100000000)));
  calibrateCommand->add_option("--runs", calibrate.runs, "timed passes per measurement (median)")
      ->capture_default_str()
      ->check(CLI::Range(1u, 100u));
  calibrateCommand->add_option("--csv", calibrate.csv, "write every measurement beside the model's prediction");

  CLI11_PARSE(app, argc, argv);
  try {
    if (*generate) return runSceneGenerate(preset, seed, floors, store);
    if (*import) return runSceneImport(importInputs, importOptions, store, ifcLights);
    if (*info) return runSceneInfo(store, SceneInfoOptions{json, !noCompress});
    if (*plan) return runScenePlan(store, planOptions);
    if (*exportCommand) return runSceneExport(store, exportOutput);
    if (*renderCommand) return runRender(render, local);
    if (*submit) return runSubmit(connect, render);
    if (*status) return runStatus(connect, job, json);
    if (*wait) return runWait(connect, job, quiet);
    if (*cancel) return runCancel(connect, job);
    if (*fetchImage) return runFetchImage(connect, job, imagePath);
    if (*shutdown) return runShutdown(connect);
    if (*keysGenerate) return runKeysGenerate(keysDirectory);
    if (*benchAccelCommand) return runBenchAccel(benchAccel);
    if (*benchPipelineCommand) return runBenchPipeline(benchPipeline);
    if (*benchQualityCommand) return runBenchQuality(benchQuality);
    if (*benchPaperCommand) return runBenchPaper(benchPaper);
    if (*calibrateCommand) return runBenchCalibrate(calibrate);
  } catch (const std::exception& e) {
    std::cerr << "portico: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
