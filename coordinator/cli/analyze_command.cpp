// `portico analyze`: a lighting analysis on this machine. The sensors come
// from a .pts file (Radiance's `x y z dx dy dz` lines) or, with --grid auto,
// are placed over the rooms' work planes; the job runs as a render does
// (runRender: a coordinator and workers, leases, progress, statistics) and
// the coordinator writes the CSV of their readings (docs/lighting-analysis.md).
#include <fmt/format.h>

#include <iostream>
#include <stdexcept>

#include "common/analysis/pts_file.h"
#include "common/analysis/pts_file_writer.h"
#include "common/analysis/result_paths.h"
#include "common/analysis/room_table.h"
#include "common/analysis/work_plane_grid.h"
#include "common/scene/store/scene_store.h"
#include "common/util/output_path.h"
#include "coordinator/cli/analysis_report.h"
#include "coordinator/cli/commands.h"

namespace portico::cli {

namespace {

// --grid auto: the store's work-plane grid, written beside the results
// (RESULTS.pts) before the job starts, so it can be given again with
// --sensors or to Radiance. The client reads the store for it.
std::vector<Sensor> gridSensors(const JobSettings& settings, const WorkPlaneGridOptions& options) {
  checkOutputPath(settings.output, OutputKind::AnalysisCsv);   // nothing is written beside a bad one
  const SceneStore store = SceneStore::open(settings.store);
  WorkPlaneGrid grid = placeWorkPlaneGrid(store, options);
  if (grid.sensors.empty())
    throw std::invalid_argument(fmt::format("--grid auto: no room of {} has a point of a {} m grid {} m from its walls",
                                            settings.store, options.spacing, options.inset));
  const std::string pts = besideResults(settings.output, ".pts");
  writePtsFile(pts, grid.sensors);
  std::cerr << fmt::format("--grid auto: {} sensors in {} rooms, {} m above their floors, {} m apart: {}\n",
                           grid.sensors.size(), grid.rooms.size(), options.height, options.spacing, pts);
  return std::move(grid.sensors);
}

}  // namespace

std::vector<Sensor> prepareAnalysis(JobSettings& settings, const AnalysisOptions& analysis) {
  if (analysis.sensorsFile.empty() == analysis.grid.empty())
    throw std::invalid_argument("an analysis needs its sensors: --sensors FILE.pts or --grid auto (one of them)");
  parseThresholds(analysis.thresholds);   // a bad list is refused before anything runs
  std::vector<Sensor> sensors =
      analysis.grid.empty() ? readPtsFile(analysis.sensorsFile) : gridSensors(settings, analysis.gridOptions);
  if (analysis.daylightFactor) {
    // DF = 100 E_in / E_out needs the sky whose E_out is the standard's.
    if (settings.daylight.sun || settings.daylight.sunTime || settings.daylight.sky != DaylightSettings::Sky::None)
      throw std::invalid_argument("--daylight-factor runs under the CIE overcast sky: not with --sun, --sun-time or --sky");
    settings.daylight.sky = DaylightSettings::Sky::Overcast;
  }
  settings.analysis = AnalysisSettings{uint32_t(sensors.size()), analysis.daylightFactor};
  return sensors;
}

void warnOfSensorsOutsideCells(const std::string& store, const std::vector<Sensor>& sensors,
                               const std::string& sensorsFile) {
  std::optional<SceneStore> scene;
  try {
    scene.emplace(SceneStore::open(store));
  } catch (const std::exception&) {
    return;   // the coordinator, which reads it, says what is wrong with it
  }
  std::vector<uint32_t> lines;
  for (const Sensor& sensor : sensors)
    if (!scene->locateCell(sensor.position)) lines.push_back(sensor.sourceLine);
  if (lines.empty()) return;
  constexpr size_t kListed = 12;
  std::string listed;
  for (size_t i = 0; i < std::min(kListed, lines.size()); ++i) listed += fmt::format("{}{}", i ? ", " : "", lines[i]);
  if (lines.size() > kListed) listed += fmt::format(" and {} more", lines.size() - kListed);
  std::cerr << fmt::format("warning: {} of the {} sensors lie outside every cell of {} ({} line{} {}): they are not "
                           "measured, and their rows of the results have empty readings\n",
                           lines.size(), sensors.size(), store, sensorsFile, lines.size() > 1 ? "s" : "", listed);
}

int runAnalyze(JobSettings settings, const AnalysisOptions& analysis, const LocalRunOptions& local) {
  const std::vector<Sensor> sensors = prepareAnalysis(settings, analysis);
  warnOfSensorsOutsideCells(settings.store, sensors, analysis.sensorsFile);
  const int status = runRender(settings, local, &sensors);
  if (status != 0) return status;
  std::cerr << fmt::format("{} sensors: {}\n", sensors.size(), settings.output);
  for (const std::string& path : writeAnalysisReport(settings.store, settings.output, parseThresholds(analysis.thresholds)))
    std::cerr << path << "\n";
  return 0;
}

}  // namespace portico::cli
