// The options and arguments of `portico render`, `portico analyze` and of the commands that
// talk to a running coordinator: submit, status, wait, cancel, priority,
// fetch-image, shutdown.
#include <CLI/CLI.hpp>

#include "coordinator/cli/analysis_report.h"
#include "coordinator/cli/work_plane_grid_command.h"

#include <memory>
#include <string>

#include "common/job/worker_tags.h"
#include "common/util/cli_bounds.h"
#include "coordinator/job_limits.h"
#include "coordinator/cli/command_table.h"
#include "coordinator/cli/commands.h"

namespace portico::cli {

namespace {

// The services `render` and `analyze` start on this machine.
void addLocalRunOptions(CLI::App& command, LocalRunOptions& local) {
  command.add_option("--workers", local.workers, "local worker processes")
      ->capture_default_str()
      ->check(wholeNumber(1, 256));
  command.add_option("--memory", local.memory, "memory of each worker (its --memory)")
      ->capture_default_str()
      ->check(workerMemory());
  command.add_flag("--keep-logs", local.keepLogs, "keep the services' logs and jobs.db");
  command.add_option("--log-level", local.logLevel, "services' log level")->capture_default_str();
  command.add_option("--keys", local.keys, "CURVE keys directory for the local services (`portico keys generate`)")
      ->check(CLI::ExistingDirectory);
}

// An analysis's sampling defaults (a sensor takes more rays than a pixel),
// set before its options are bound so that --help shows them.
void useAnalysisDefaults(JobSettings& settings) {
  settings.spp = kAnalysisSpp;
  settings.gather = kAnalysisGather;
  settings.lightSamples = kAnalysisLightSamples;
}

// Where an analysis's sensors come from, and what it reports.
void addAnalysisOptions(CLI::App& command, AnalysisOptions& analysis) {
  command.add_option("--sensors", analysis.sensorsFile,
                     "the sensors: a Radiance .pts file, one `x y z dx dy dz` a line (a point in metres and the "
                     "direction its measuring plane faces)")
      ->check(CLI::ExistingFile);
  auto* grid = command
                   .add_option("--grid", analysis.grid,
                               "auto: work-plane grids over every room instead of --sensors (written beside the "
                               "results as .pts; --grid-* options)")
                   ->check(CLI::IsMember({"auto"}));
  for (CLI::Option* option : addWorkPlaneGridOptions(command, analysis.gridOptions)) option->needs(grid);
  command.add_flag("--daylight-factor", analysis.daylightFactor,
                   "under the CIE overcast sky, report each sensor's daylight factor DF = 100 E / E_out (%), E_out "
                   "the sky's unobstructed horizontal illuminance");
}

void addAnalyze(CLI::App& app, CommandTable& table) {
  struct Options {
    JobSettings settings;
    AnalysisOptions analysis;
    LocalRunOptions local;
  };
  auto o = std::make_shared<Options>();
  useAnalysisDefaults(o->settings);
  auto* analyze = app.add_subcommand(
      "analyze", "lighting analysis: illuminance (lux) at sensors, as a job on local workers; writes a CSV");
  analyze->add_option("STORE", o->settings.store, "scene store directory")->required()->check(CLI::ExistingDirectory);
  analyze->add_option("-o,--output", o->settings.output, "the results: a .csv, one row per sensor")->required();
  addAnalysisOptions(*analyze, o->analysis);
  addThresholdsOption(*analyze, o->analysis.thresholds);
  addLightingOptions(*analyze, o->settings, "samples per sensor");
  addLocalRunOptions(*analyze, o->local);
  table.add(analyze, [o] { return runAnalyze(o->settings, o->analysis, o->local); });
}

void addRender(CLI::App& app, CommandTable& table) {
  struct Options {
    JobSettings render;
    LocalRunOptions local;
    ViewsOptions views;
  };
  auto o = std::make_shared<Options>();
  auto* renderCommand = app.add_subcommand("render", "render locally: starts a coordinator and workers");
  addRenderOptions(*renderCommand, o->render);
  addLocalRunOptions(*renderCommand, o->local);
  auto* views = renderCommand->add_option(
      "--views", o->views.file,
      "a JSON file of views (name, and camera (a store camera) or look_from, look_at, optional up, fov; optional "
      "width, height, spp) rendered after one photon pass; -o then names a directory, each image is "
      "DIR/<name>.<format>");
  views->check(CLI::ExistingFile);
  renderCommand->add_option("--format", o->views.format, "with --views: the images' format")
      ->capture_default_str()
      ->check(CLI::IsMember({"exr", "png", "hdr", "tif", "tiff", "jpg", "jpeg"}))
      ->needs(views);
  table.add(renderCommand,
            [o] { return o->views.file.empty() ? runRender(o->render, o->local) : runViews(o->render, o->local, o->views); });
}

// `submit`'s place in the queue: --priority and --require.
void addPlacementOptions(CLI::App& command, Placement& placement) {
  command.add_option("--priority", placement.priority,
                     fmt::format("the job's priority, {} to {}: its leases come before those of lower priorities "
                                 "(equal ones: the older job first); the same bits whatever it is",
                                 limits::kMinPriority, limits::kMaxPriority))
      ->capture_default_str()
      ->check(wholeNumber(limits::kMinPriority, limits::kMaxPriority));
  command.add_option("--require", placement.requiredTags,
                     "a worker tag the job's workers must have (repeatable; `portico-worker --tag NAME`)")
      ->check(CLI::Validator([](std::string& tag) { return tagNameProblem(tag); }, "NAME"));
}

// The coordinator to reach and the job asked about (status: 0 for every job).
struct JobOptions {
  ConnectOptions connect;
  uint64_t job = 0;
};

void addSubmit(CLI::App& app, CommandTable& table) {
  struct Options {
    ConnectOptions connect;
    JobSettings render;
    Placement placement;
    bool analyze = false;
    AnalysisOptions analysis;
  };
  auto o = std::make_shared<Options>();
  auto* submit = app.add_subcommand("submit", "submit a job to a running coordinator; prints its id");
  addConnectOptions(*submit, o->connect);
  addRenderOptions(*submit, o->render);
  addPlacementOptions(*submit, o->placement);
  submit->add_flag("--analyze", o->analyze,
                   "a lighting analysis (as `portico analyze`): -o names its .csv; needs --sensors or --grid");
  addAnalysisOptions(*submit, o->analysis);
  table.add(submit, [o, submit] {
    if (!o->analyze) {
      if (!o->analysis.sensorsFile.empty() || !o->analysis.grid.empty() || o->analysis.daylightFactor)
        throw std::invalid_argument("--sensors, --grid and --daylight-factor need --analyze");
      return runSubmit(o->connect, o->render, o->placement);
    }
    // The analysis's sampling defaults where the command line gives none.
    const JobSettings defaults = [] {
      JobSettings d;
      useAnalysisDefaults(d);
      return d;
    }();
    if (submit->get_option("--spp")->count() == 0) o->render.spp = defaults.spp;
    if (submit->get_option("--gather")->count() == 0) o->render.gather = defaults.gather;
    if (submit->get_option("--light-samples")->count() == 0) o->render.lightSamples = defaults.lightSamples;
    const std::vector<Sensor> sensors = prepareAnalysis(o->render, o->analysis);
    warnOfSensorsOutsideCells(o->render.store, sensors, o->analysis.sensorsFile);
    return runSubmit(o->connect, o->render, o->placement, &sensors);
  });
}

void addStatus(CLI::App& app, CommandTable& table) {
  struct Options : JobOptions {
    bool json = false;
  };
  auto o = std::make_shared<Options>();
  auto* status = app.add_subcommand("status", "show a job's progress (or every job)");
  addConnectOptions(*status, o->connect);
  status->add_option("JOB", o->job, "job id");
  status->add_flag("--json", o->json, "one JSON object on stdout");
  table.add(status, [o] { return runStatus(o->connect, o->job, o->json); });
}

void addWait(CLI::App& app, CommandTable& table) {
  struct Options : JobOptions {
    bool quiet = false;
  };
  auto o = std::make_shared<Options>();
  auto* wait = app.add_subcommand("wait", "block until a job ends; exit 0 if it is done");
  addConnectOptions(*wait, o->connect);
  wait->add_option("JOB", o->job, "job id")->required();
  wait->add_flag("--quiet", o->quiet, "no progress lines");
  table.add(wait, [o] { return runWait(o->connect, o->job, o->quiet); });
}

void addCancel(CLI::App& app, CommandTable& table) {
  auto o = std::make_shared<JobOptions>();
  auto* cancel = app.add_subcommand("cancel", "cancel a job");
  addConnectOptions(*cancel, o->connect);
  cancel->add_option("JOB", o->job, "job id")->required();
  table.add(cancel, [o] { return runCancel(o->connect, o->job); });
}

void addPriority(CLI::App& app, CommandTable& table) {
  struct Options : JobOptions {
    int32_t priority = 0;
  };
  auto o = std::make_shared<Options>();
  auto* priority = app.add_subcommand(
      "priority", "change a waiting or running job's priority: its next leases follow it (those in flight finish)");
  addConnectOptions(*priority, o->connect);
  priority->add_option("JOB", o->job, "job id")->required()->check(wholeNumber(1, INT64_MAX));
  priority->add_option("PRIORITY", o->priority, "the new priority (higher runs first)")
      ->required()
      ->check(wholeNumber(limits::kMinPriority, limits::kMaxPriority));
  table.add(priority, [o] { return runPriority(o->connect, o->job, o->priority); });
}

void addFetchImage(CLI::App& app, CommandTable& table) {
  struct Options : JobOptions {
    std::string imagePath;
  };
  auto o = std::make_shared<Options>();
  auto* fetchImage = app.add_subcommand(
      "fetch-image", "write a done job's image (and its .json statistics) as this user, e.g. where the coordinator could not");
  addConnectOptions(*fetchImage, o->connect);
  fetchImage->add_option("JOB", o->job, "job id")->required();
  fetchImage->add_option("-o,--output", o->imagePath, "where to write it (default: the job's own output path)");
  table.add(fetchImage, [o] { return runFetchImage(o->connect, o->job, o->imagePath); });
}

void addShutdown(CLI::App& app, CommandTable& table) {
  auto o = std::make_shared<ConnectOptions>();
  auto* shutdown = app.add_subcommand("shutdown", "stop a running coordinator (needs the operator key: --keys DIR "
                                                  "with operator.secret, or its own user on ipc://)");
  addConnectOptions(*shutdown, *o);
  table.add(shutdown, [o] { return runShutdown(*o); });
}

}  // namespace

void addJobCommands(CLI::App& app, CommandTable& table) {
  addRender(app, table);
  addAnalyze(app, table);
  addReportCommand(app, table);
  addSubmit(app, table);
  addStatus(app, table);
  addWait(app, table);
  addCancel(app, table);
  addPriority(app, table);
  addFetchImage(app, table);
  addShutdown(app, table);
  addDashboardCommand(app, table);
}

}  // namespace portico::cli
