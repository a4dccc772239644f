// The options and actions of `portico bench`'s subcommands, one registration
// function per benchmark.
#include "coordinator/cli/bench/bench_command_line.h"

#include <memory>

#include "common/util/cli_bounds.h"
#include "coordinator/cli/bench/bench_accel.h"
#include "coordinator/cli/bench/bench_analyze.h"
#include "coordinator/cli/bench/bench_calibrate.h"
#include "coordinator/cli/bench/bench_cluster.h"
#include "coordinator/cli/bench/bench_coordinator.h"
#include "coordinator/cli/bench/bench_lights.h"
#include "coordinator/cli/bench/bench_paper.h"
#include "coordinator/cli/bench/bench_pipeline.h"
#include "coordinator/cli/bench/bench_quality.h"
#include "coordinator/cli/bench/simulated_workers.h"
#include "coordinator/cli/command_table.h"

namespace portico::cli {

namespace {

void addAccel(CLI::App& bench, CommandTable& table) {
  auto o = std::make_shared<BenchAccelOptions>();
  auto* benchAccelCommand =
      bench.add_subcommand("accel", "build time and tracing speed of the accelerators on furnished cells");
  benchAccelCommand->add_option("--sizes", o->sizes, "triangle counts of the cells (e.g. 1000,10k,1M)")
      ->capture_default_str();
  benchAccelCommand->add_option("--rays", o->rays, "rays per kind (photon, camera) and size")
      ->capture_default_str();
  benchAccelCommand
      ->add_option("--specs", o->specs,
                   "accelerator specs, comma-separated (name=value items belong to the spec before them; ';' "
                   "also separates); kinds not in this build are skipped")
      ->capture_default_str();
  benchAccelCommand->add_option("--csv", o->csv, "write one row per structure, size and ray kind");
  benchAccelCommand->add_option("--plot", o->plot, "write a PNG: build time and Mrays/s against triangles");
  benchAccelCommand->add_option("--seed", o->seed, "seed of the furnishing and of the rays")
      ->capture_default_str();
  benchAccelCommand->add_option("--runs", o->runs, "timed runs per measurement (the median is reported)")
      ->capture_default_str()
      ->check(CLI::Range(1u, 100u));
  benchAccelCommand
      ->add_option("--embree-threads", o->embreeThreads,
                   "threads of Embree's builder (0: every core); 1 compares like with like")
      ->capture_default_str();
  table.add(benchAccelCommand, [o] { return runBenchAccel(*o); });
}

void addQuality(CLI::App& bench, CommandTable& table) {
  auto o = std::make_shared<BenchQualityOptions>();
  auto* benchQualityCommand = bench.add_subcommand(
      "quality", "error against time on a reference scene: a ladder of render settings (docs/image-quality.md)");
  benchQualityCommand
      ->add_option("DIR", o->sceneDirectory,
                   "folder of reference.exr and scene.json (a reference scene) or view.json (a generated building's "
                   "camera: tests/scenes/views)")
      ->required()
      ->check(CLI::ExistingDirectory);
  benchQualityCommand->add_option("--settings", o->settings,
                                  "portico render arguments per rung, rungs separated by ';'")
      ->capture_default_str();
  benchQualityCommand->add_option("--workers", o->workers, "workers of each render (and Mitsuba's threads)")
      ->capture_default_str();
  benchQualityCommand->add_flag("--mitsuba", o->mitsuba,
                                "also render the scene with Mitsuba 3's path tracer, in the same run "
                                "(deploy/install-deps.sh --peers installs it)");
  benchQualityCommand->add_option("--mitsuba-spp", o->mitsubaSpp, "Mitsuba's sample counts, comma-separated")
      ->capture_default_str();
  benchQualityCommand->add_option("--mitsuba-python", o->mitsubaPython,
                                  "a python with mitsuba and drjit (default: $MITSUBA_VENV/bin/python, else "
                                  "~/.local/share/portico/mitsuba-venv/bin/python)");
  benchQualityCommand->add_flag("--luxcore", o->luxcore,
                                "also render the scene with LuxCoreRender, in the same run (deploy/install-deps.sh "
                                "installs pyluxcore in the sources' .venv)");
  benchQualityCommand->add_option("--luxcore-spp", o->luxcoreSpp, "LuxCoreRender's sample counts, comma-separated")
      ->capture_default_str();
  benchQualityCommand
      ->add_option("--luxcore-photongi", o->luxcorePhotonGi,
                   "photons of LuxCoreRender's PhotonGI indirect cache (0: its plain path tracer)")
      ->capture_default_str();
  benchQualityCommand->add_option("--csv", o->csv, "write one row per setting");
  benchQualityCommand->add_option("--plot", o->plot, "write a PNG: block RMSE and worst block against seconds");
  table.add(benchQualityCommand, [o] { return runBenchQuality(*o); });
}

void addLights(CLI::App& bench, CommandTable& table) {
  auto o = std::make_shared<BenchLightsOptions>();
  auto* command = bench.add_subcommand(
      "lights", "render phase and error of one view with the light tree and the scan, interleaved (docs/many-lights.md)");
  command->add_option("STORE", o->store, "scene store")->required()->check(CLI::ExistingDirectory);
  command->add_option("--camera", o->camera, "store camera of the view (portico scene info lists them)")->required();
  command->add_option("--reference", o->reference, "converged EXR of the same view, photons and size (default: render one)");
  command->add_option("--keep-reference", o->keepReference, "where to keep the reference rendered here");
  command->add_option("--reference-spp", o->referenceSpp, "samples per pixel of the reference rendered here")
      ->capture_default_str()
      ->check(CLI::Range(1u, 1u << 16));
  command->add_option("--reference-sampler", o->referenceSampler, "light sampler of the reference rendered here")
      ->capture_default_str()
      ->check(CLI::IsMember({"tree", "scan"}));
  command->add_option("--photons", o->photons, "photons of every run")->capture_default_str();
  command->add_option("--seed", o->seed, "seed of every run (the same photons in each)")->capture_default_str();
  command->add_option("--spp", o->spp, "samples per pixel of the measured runs")->capture_default_str();
  command->add_option("--tree-spp", o->treeSpp, "samples per pixel of the tree's runs (default: --spp)");
  command->add_option("--gather", o->gather, "final-gather rays per hit")->capture_default_str();
  command->add_option("--width", o->width, "image width")->capture_default_str();
  command->add_option("--height", o->height, "image height")->capture_default_str();
  command->add_option("--workers", o->workers, "workers of each render")->capture_default_str();
  command->add_option("--memory", o->memory, "cache budget per worker")->capture_default_str()->check(workerMemory());
  command->add_option("--accel", o->accel, "accelerator of the photon pass")->capture_default_str();
  command->add_option("--runs", o->runs, "runs per sampler, interleaved (medians reported)")
      ->capture_default_str()
      ->check(CLI::Range(1u, 100u));
  command->add_option("--csv", o->csv, "write one row per run");
  table.add(command, [o] { return runBenchLights(*o); });
}

void addPipeline(CLI::App& bench, CommandTable& table) {
  auto o = std::make_shared<BenchPipelineOptions>();
  auto* benchPipelineCommand = bench.add_subcommand(
      "pipeline", "one photon pass over a generated building: in-core Embree (2 threads) vs portico (1, 2 workers)");
  benchPipelineCommand->add_option("--preset", o->preset, "building preset: l-shape, z-building, octagon, soda-hall, tower")
      ->required();
  benchPipelineCommand->add_option("--photons", o->photons,
                                   "photons of the pass (default: the paper's workload, 50 000 per light, at most 10 M: "
                                   "7.75 M for the octagon, 1.2 M for the l-shape)");
  benchPipelineCommand->add_option("--store", o->store,
                                   "scene store to reuse, or to generate the building into and keep (default: a temporary one)");
  benchPipelineCommand->add_option("--floors", o->floors, "floors of the tower preset");
  benchPipelineCommand->add_option("--scene-seed", o->sceneSeed, "furnishing seed of the building")
      ->capture_default_str();
  benchPipelineCommand->add_option("--seed", o->seed, "seed of the photon pass")->capture_default_str();
  benchPipelineCommand->add_option("--modes", o->modes, "modes, comma-separated (portico-Nw for any N)")
      ->capture_default_str();
  benchPipelineCommand->add_option("--accel", o->accel, "portico's accelerator spec")->capture_default_str();
  benchPipelineCommand->add_option("--memory", o->memory, "cache budget per portico worker")
      ->capture_default_str()
      ->check(workerMemory());
  benchPipelineCommand->add_option("--runs", o->runs, "runs per mode, interleaved (the median is reported)")
      ->capture_default_str()
      ->check(CLI::Range(1u, 100u));
  benchPipelineCommand->add_option("--csv", o->csv, "write one row per mode");
  benchPipelineCommand->add_option("--plot", o->plot, "write a PNG bar chart of photons/s");
  table.add(benchPipelineCommand, [o] { return runBenchPipeline(*o); });
}

void addPaper(CLI::App& bench, CommandTable& table) {
  auto o = std::make_shared<BenchPaperOptions>();
  auto* benchPaperCommand = bench.add_subcommand(
      "paper", "rerun every experiment of Fradin & Meneveaux 2006 section 6 through the pipeline (docs/paper-benchmark.md)");
  benchPaperCommand->add_flag("--quick", o->quick, "a reduced version of every experiment (a few minutes)");
  benchPaperCommand->add_flag("--smoke", o->smoke, "the smallest version, l-shape only (the ctest)")
      ->group("");   // hidden
  benchPaperCommand->add_option("--out", o->out, "directory of the CSVs, PNGs, summary.json and stores/")
      ->capture_default_str();
  benchPaperCommand->add_option("--buildings", o->buildings,
                                "buildings, comma-separated (l-shape, z-building, octagon, soda-hall, tower); "
                                "default: the mode's");
  benchPaperCommand->add_option("--experiments", o->experiments,
                                "experiments, comma-separated (default: all; fig4_5_grid_resolution, fig6_hgrid_init, "
                                "table3_kd_depth, fig7_8_kd_heuristics, fig9_best_topological, table4_uniform_cells, "
                                "fig11_topological_vs_uniform, auto_vs_fixed)");
  benchPaperCommand->add_option("--photons-per-light", o->photonsPerLight,
                                "photons per light of the passes (default: quick 300, otherwise 1000; the 'few' "
                                "count is 2/5 of it)");
  benchPaperCommand->add_option("--workers", o->workers, "workers of each render")->capture_default_str();
  benchPaperCommand->add_option("--runs", o->runs, "runs per measurement (the median is reported)")
      ->capture_default_str()
      ->check(CLI::Range(1u, 100u));
  benchPaperCommand->add_option("--seed", o->seed, "seed of the photon passes")->capture_default_str();
  benchPaperCommand->add_option("--scene-seed", o->sceneSeed, "furnishing seed of the buildings")
      ->capture_default_str();
  benchPaperCommand->add_option("--memory", o->memory, "cache budget per worker")
      ->capture_default_str()
      ->check(workerMemory());
  benchPaperCommand->add_option("--timeout", o->timeoutSeconds,
                                "seconds a run may take before it is stopped and marked failed (default: the mode's)");
  table.add(benchPaperCommand, [o] { return runBenchPaper(*o); });
}

void addCalibrate(CLI::App& bench, CommandTable& table) {
  auto o = std::make_shared<CalibrateOptions>();
  auto* calibrateCommand = bench.add_subcommand(
      "calibrate", "fit the --accel auto cost model to this machine and store it where workers look");
  calibrateCommand->add_option("-o,--out", o->output,
                               "calibration file (default: $PORTICO_CALIBRATION, else ~/.cache/portico/calibration.json)");
  calibrateCommand->add_option("--preset", o->preset, "building whose cells are measured")->capture_default_str();
  calibrateCommand->add_option("--store", o->store, "measure this scene store's cells instead");
  calibrateCommand->add_option("--max-cells", o->maxCells, "cells of the building, spread over its sizes")
      ->capture_default_str();
  calibrateCommand->add_option("--sizes", o->sizes, "triangle counts of the furnished halls also measured")
      ->capture_default_str();
  calibrateCommand->add_option("--rays", o->rays, "photon-like rays per cell")->capture_default_str()
      ->check(CLI::Range(uint64_t(100), uint64_t(100000000)));
  calibrateCommand->add_option("--runs", o->runs, "timed passes per measurement (median)")
      ->capture_default_str()
      ->check(CLI::Range(1u, 100u));
  calibrateCommand->add_option("--csv", o->csv, "write every measurement beside the model's prediction");
  table.add(calibrateCommand, [o] { return runBenchCalibrate(*o); });
}

void addCluster(CLI::App& bench, CommandTable& table) {
  auto o = std::make_shared<BenchClusterOptions>();
  auto* command = bench.add_subcommand(
      "cluster", "the cluster model: finished jobs' lease logs replayed for N workers (docs/large-buildings.md)");
  command->add_option("RECORDS", o->records, "JOBS_DB[:JOB] of finished runs (default job: the newest done one)")
      ->required();
  command->add_option("--workers", o->workers, "worker counts to predict from the first record")->capture_default_str();
  command->add_option("--memory", o->memory, "each modelled worker's --memory when the record has none")
      ->capture_default_str();
  command->add_option("--latency-us", o->latencyMicros, "one-way network latency")->capture_default_str();
  command
      ->add_option("--host-cores", o->hostCores,
                   "the coordinator and the workers share this many cores (the machine the records ran on); "
                   "0: a machine each; measured: the cores the predicted run's job had (its CPU over its time)")
      ->capture_default_str();
  command
      ->add_option("--work-scale", o->workScale,
                   "the records' photon-pass tracing work times this (F times the photons), the render as recorded")
      ->capture_default_str()
      ->check(CLI::Range(1e-3, 1e6));
  command
      ->add_option("--lease-scale", o->leaseScale,
                   "each lease's work times this (the coordinator's lease seconds and --lease-rays): fewer, longer "
                   "leases")
      ->capture_default_str()
      ->check(CLI::Range(1e-2, 1e4));
  command->add_option("--coordinator-bench", o->coordinatorBench,
                      "`portico bench coordinator --csv` output: charge the coordinator its measured CPU per lease and "
                      "bytes per ray at each worker count (interpolated) instead of each record's CPU");
  command
      ->add_option("--coordinator-ms-per-lease", o->coordinatorMsPerLease,
                   "the coordinator's CPU per lease instead of each record's (e.g. `portico bench coordinator`'s)")
      ->check(CLI::Range(0.0, 1e4));
  command
      ->add_option("--bytes-per-ray", o->bytesPerRay,
                   "bytes a lease moves through the coordinator per ray of its work (`bench coordinator`'s "
                   "bytes_per_work), charged on its link")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1e6));
  command->add_option("--link-gbit", o->linkGbit, "the coordinator's network link, Gbit/s")
      ->capture_default_str()
      ->check(CLI::Range(1e-3, 1e4));
  command->add_option("--csv", o->csv, "write one row per prediction");
  table.add(command, [o] { return runBenchCluster(*o); });
}

void addAnalyze(CLI::App& bench, CommandTable& table) {
  auto o = std::make_shared<BenchAnalyzeOptions>();
  auto* command = bench.add_subcommand(
      "analyze", "lighting analysis: sensor error against time beside Radiance's rtrace -I on a reference scene, or "
                 "every room of generated buildings (docs/radiance.md)");
  command->add_option("SCENE_DIR", o->sceneDirectory,
                      "folder of scene.json and sensors.pts (render_args.txt, radiance_reference.csv if any)")
      ->check(CLI::ExistingDirectory);
  command->add_option("--radiance-settings", o->radianceSettings, "rtrace options per rung, rungs separated by ';'")
      ->capture_default_str();
  command->add_option("--radiance-reference", o->radianceReference,
                      "rtrace options of Radiance's converged reference, when SCENE_DIR has no radiance_reference.csv")
      ->capture_default_str();
  command->add_option("--portico-settings", o->porticoSettings,
                      "portico analyze arguments per rung, rungs separated by ';'")
      ->capture_default_str();
  command->add_option("--portico-reference", o->porticoReference, "portico analyze arguments of its converged reference")
      ->capture_default_str();
  command->add_option("--workers", o->workers, "workers of each portico analyze")->capture_default_str();
  command->add_option("--csv", o->csv, "write one row per rung (or per building)");
  command->add_option("--plot", o->plot, "write a PNG: each program's error against seconds");
  command->add_option("--buildings", o->buildings,
                      "the scale run instead: generated buildings, PRESET[:FLOORS] comma-separated (tower:10,octagon)");
  command->add_option("--stores", o->storeDirectory,
                      "with --buildings: generate the stores here and reuse them when present (default: a temporary "
                      "folder)");
  command->add_option("--analyze-args", o->analyzeArguments, "with --buildings: more portico analyze arguments");
  command->add_option("--memory", o->memory, "with --buildings: each worker's memory budget")->capture_default_str();
  table.add(command, [o] { return runBenchAnalyze(*o); });
}


// The shape of the simulated workers' Results (simulated_result.h), for the
// bench and for each of its worker processes.
void addResultShape(CLI::App& command, ResultShape& shape) {
  command.add_option("--deposits-per-photon", shape.depositsPerPhoton,
                     "photon records (deposits and portal copies) per photon a lease starts")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 100.0));
  command.add_option("--photon-crossings", shape.photonCrossings, "photons handed on to a neighbouring cell per photon")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 0.95));
  command.add_option("--camera-crossings", shape.cameraCrossings, "render rays handed on per camera ray")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 0.95));
  command.add_option("--max-depth", shape.maxDepth, "portals a handed-on ray crosses at most")
      ->capture_default_str()
      ->check(CLI::Range(1u, 1000u));
  command.add_option("--rays-per-second", shape.raysPerSecond,
                     "the speed each simulated worker reports (the coordinator sizes leases to ~1 s of it)")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 1e12));
  command.add_flag("--miscount", shape.miscount, "fault injection: photon Results that do not add up")->group("");
}

void addCoordinator(CLI::App& bench, CommandTable& table) {
  auto o = std::make_shared<BenchCoordinatorOptions>();
  auto* command = bench.add_subcommand(
      "coordinator", "the real coordinator driven by N simulated workers: leases/s, CPU per lease, latency "
                     "(docs/coordinator-benchmark.md)");
  auto* workers = command->add_option("--workers", o->workers, "simulated worker counts, one run each")
                      ->capture_default_str();
  command->add_option("--preset", o->preset, "building preset of the job")->capture_default_str();
  auto* floors = command->add_option("--floors", o->floors, "floors of the tower preset")->capture_default_str();
  command->add_option("--scene-seed", o->sceneSeed, "furnishing seed of the building")->capture_default_str();
  command->add_option("--store", o->store, "scene store to reuse, or to generate the building into and keep");
  auto* photons = command->add_option("--photons-per-light", o->photonsPerLight, "the job's photons per light")
                      ->capture_default_str()
                      ->check(CLI::Range(uint64_t(1), uint64_t(1000000)));
  command->add_option("--lease-rays", o->leaseRays, "the coordinator's --lease-rays")
      ->capture_default_str()
      ->check(CLI::Range(int64_t(1), int64_t(1000000)));
  command->add_option("--width", o->width, "image width of the job's render phase")->capture_default_str();
  command->add_option("--height", o->height, "image height")->capture_default_str();
  command->add_option("--workers-per-process", o->workersPerProcess, "simulated workers per process")
      ->capture_default_str();
  command->add_flag("!--no-deposit-regions", o->depositRegions,
                    "the simulated workers send deposits in their Results (workers on other machines) instead of "
                    "writing them into their regions");
  addResultShape(*command, o->shape);
  command->add_option("--timeout", o->timeoutSeconds, "seconds one run may take")->capture_default_str();
  command->add_flag("--quick", o->quick, "2 floors, 200 photons per light, --workers 4,16 (unless given)");
  command->add_flag("--keep", o->keep, "keep each run's folder (jobs.db, logs, the workers' reports)");
  command->add_option("--csv", o->csv, "write one row per worker count");
  command->add_option("--plot", o->plot, "write a PNG: leases/s, latency and CPU per lease against workers");
  table.add(command, [o, workers, floors, photons] {
    return runBenchCoordinator(*o, workers->count() > 0, floors->count() > 0, photons->count() > 0);
  });

  auto s = std::make_shared<SimulatedWorkersOptions>();
  auto* simulated = bench.add_subcommand("simulated-workers", "one process of `bench coordinator`'s simulated workers");
  simulated->group("");   // hidden: the bench starts it
  simulated->add_option("--connect", s->endpoint, "the coordinator's endpoint")->required();
  simulated->add_option("--count", s->count, "workers in this process")->capture_default_str();
  simulated->add_option("--first", s->first, "the first worker's number")->capture_default_str();
  simulated->add_option("--report", s->report, "where the totals and samples go")->required();
  simulated->add_flag("!--no-deposit-regions", s->depositRegions, "send deposits in the Results");
  addResultShape(*simulated, s->shape);
  table.add(simulated, [s] { return runSimulatedWorkers(*s); });
}
}  // namespace

void addBenchCommands(CLI::App& app, CommandTable& table) {
  auto* bench = app.add_subcommand("bench", "measure portico's parts");
  bench->require_subcommand(1);
  addAccel(*bench, table);
  addQuality(*bench, table);
  addAnalyze(*bench, table);
  addPipeline(*bench, table);
  addLights(*bench, table);
  addPaper(*bench, table);
  addCalibrate(*bench, table);
  addCluster(*bench, table);
  addCoordinator(*bench, table);
}

}  // namespace portico::cli
