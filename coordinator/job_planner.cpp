#include "coordinator/job_planner.h"

#include <capnp/message.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "common/accel/accelerator.h"
#include "common/analysis/sensor_film.h"
#include "common/job/sun_time.h"
#include "common/net/message.h"
#include "common/net/job_spec_wire.h"
#include "common/transport/daylight_openings.h"
#include "common/transport/photon_shares.h"
#include "common/transport/sky_model.h"
#include "common/scene/store/floor_levels.h"
#include "common/scene/store/portal_geometry.h"
#include "common/transport/sampling.h"
#include "coordinator/analysis_sensors.h"
#include "coordinator/job_limits.h"

namespace portico {

namespace {

template <typename T>
void requireAtMost(const char* what, T value, T most) {
  if (value > most) throw std::invalid_argument(fmt::format("{} {} is too large: at most {}", what, value, most));
}

// Every portal is tested by every ray in its cells: a cell with too many
// (a door repeated a million times) makes leases that never end. Counting
// is linear and needs a counter per cell; duplicates are found at import
// and by `scene info` (common/scene/store/scene_validation.h).
void checkPortalsPerCell(const SceneStore& scene) {
  std::vector<uint32_t> perCell(scene.cells().size(), 0);
  for (const Portal& portal : scene.portals())
    for (uint32_t cell : {portal.cellA, portal.cellB})
      if (cell < perCell.size() && ++perCell[cell] > kMaxPortalsPerCell)
        throw std::invalid_argument(fmt::format("scene {}: cell {} has more than {} portals (duplicates?)",
                                                scene.directory(), cell, kMaxPortalsPerCell));
}
// A hand-made submit may hold anything: NaN, a negative or zero target, an
// endless time limit.
void validateRenderPasses(const JobSettings& settings) {
  if (settings.targetError && !(*settings.targetError > 0 && *settings.targetError <= limits::kMaxTargetError))
    throw std::invalid_argument(fmt::format("target error {} must be a number above 0 and at most {:g}",
                                            *settings.targetError, limits::kMaxTargetError));
  if (settings.timeLimitSeconds &&
      !(*settings.timeLimitSeconds > 0 && *settings.timeLimitSeconds <= limits::kMaxTimeLimitSeconds))
    throw std::invalid_argument(fmt::format("time limit {} s must be a number above 0 and at most {:g} s",
                                            *settings.timeLimitSeconds, limits::kMaxTimeLimitSeconds));
  if (settings.maxPasses < 1 || settings.maxPasses > limits::kMaxPasses)
    throw std::invalid_argument(
        fmt::format("max passes {} must be between 1 and {}", settings.maxPasses, limits::kMaxPasses));
}

// An analysis job's own rules: its sensors are its film's rows; it renders
// no image, in one pass.
void validateAnalysis(const JobSettings& settings) {
  const AnalysisSettings& analysis = *settings.analysis;
  if (analysis.sensors == 0 || analysis.sensors > kMaxSensors)
    throw std::invalid_argument(fmt::format("an analysis of {} sensors: it needs 1 to {}", analysis.sensors, kMaxSensors));
  if (settings.width != kSensorFilmColumns || settings.height != analysis.sensors)
    throw std::invalid_argument(fmt::format("an analysis's film is {}x{}, not {}x{}", kSensorFilmColumns,
                                            analysis.sensors, settings.width, settings.height));
  if (uint64_t(analysis.sensors) * settings.spp > limits::kMaxCameraSamples)
    throw std::invalid_argument(fmt::format("{} sensors at {} samples each is too many: at most {}", analysis.sensors,
                                            settings.spp, limits::kMaxCameraSamples));
  if (settings.progressive() || settings.maxPasses != 1)
    throw std::invalid_argument("an analysis runs in one pass: no --target-error, --time-limit or --max-passes");
  if (settings.aov != JobSettings::Aov::Radiance) throw std::invalid_argument("an analysis has no --aov");
  if (analysis.daylightFactor) {
    if (settings.daylight.sun || !SkyModel(settings.daylight).horizontalSkyLux())
      throw std::invalid_argument(
          "--daylight-factor needs a sky whose outdoor illuminance is known in closed form (the CIE overcast or a "
          "uniform sky) and no sun");
  }
}

bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

std::string text(const Vec3& v) { return fmt::format("{},{},{}", v.x, v.y, v.z); }

// A store camera as a job's camera, exactly as stored (its cell too).
JobCamera jobCameraOf(const Camera& stored) {
  return {stored.origin, stored.target, stored.up, stored.fovYDegrees, stored.cell};
}

// The store's camera, or the job's with its automatic parts (up, fov) taken
// from the store's and its cell located; refuses, naming the option, a
// camera that cannot trace.
JobCamera resolveCamera(const std::optional<JobCamera>& chosen, const SceneStore& scene) {
  const Camera& own = scene.camera();
  const JobCamera stores = jobCameraOf(own);
  // The store's camera, given or left out, is used exactly as stored.
  if (!chosen || *chosen == stores) return stores;
  // A named store camera, resolved already, keeps its stored cell.
  for (const Camera& named : scene.cameras())
    if (*chosen == jobCameraOf(named)) return *chosen;
  JobCamera camera = *chosen;
  if (camera.up == Vec3(0.0f)) camera.up = own.up;
  if (camera.fovYDegrees == 0) camera.fovYDegrees = own.fovYDegrees;
  if (!finite(camera.lookFrom)) throw std::invalid_argument(fmt::format("--look-from {} is not a point", text(camera.lookFrom)));
  if (!finite(camera.lookAt)) throw std::invalid_argument(fmt::format("--look-at {} is not a point", text(camera.lookAt)));
  if (camera.lookAt == camera.lookFrom)
    throw std::invalid_argument(fmt::format("--look-at {} is the --look-from point: no direction to look", text(camera.lookAt)));
  const Vec3 forward = normalize(camera.lookAt - camera.lookFrom);
  if (!finite(camera.up) || !(length(cross(forward, normalize(camera.up))) > 1e-4f))
    throw std::invalid_argument(fmt::format("--up {} is not a direction across the view", text(camera.up)));
  if (!(camera.fovYDegrees > 0 && camera.fovYDegrees < 180))
    throw std::invalid_argument(fmt::format("--fov {} must be above 0 and below 180 degrees", camera.fovYDegrees));
  // The store's eye keeps the store's cell (where overlapping cells meet,
  // the one the store recorded); any other eye is in the smallest cell
  // containing it. Either way resolving again finds the same cell.
  if (camera.lookFrom == own.origin) {
    camera.cell = own.cell;
  } else {
    const std::optional<uint32_t> cell = scene.locateCell(camera.lookFrom);
    if (!cell)
      throw std::invalid_argument(fmt::format("--look-from {} is outside every cell of scene {}",
                                              text(camera.lookFrom), scene.directory()));
    camera.cell = *cell;
  }
  return camera;
}

// The store camera `name`, or a one-line refusal naming it and a few that exist.
const Camera& namedCamera(const std::string& name, const SceneStore& scene) {
  if (name.size() > kMaxCameraNameBytes)
    throw std::invalid_argument(fmt::format("--camera: a name of {} bytes; store cameras have at most {}", name.size(),
                                            kMaxCameraNameBytes));
  if (const Camera* camera = scene.findCamera(name)) return *camera;
  constexpr size_t kListed = 6;
  std::string known;
  for (size_t k = 0; k < std::min(kListed, scene.cameras().size()); ++k)
    known += (k ? ", " : "") + scene.cameras()[k].name;
  if (scene.cameras().size() > kListed) known += fmt::format(" and {} more", scene.cameras().size() - kListed);
  throw std::invalid_argument(fmt::format("--camera '{}': scene {} has no camera of that name (it has {}; `portico "
                                          "scene info` lists them)",
                                          name, scene.directory(), known));
}
}  // namespace

uint64_t defaultPhotonCount(size_t lightCount) {
  return std::clamp<uint64_t>(kDefaultPhotonsPerLight * lightCount, kMinDefaultPhotons, kMaxDefaultPhotons);
}

JobSettings resolveJobSettings(JobSettings settings, const SceneStore& scene) {
  const JobSettings defaults;
  // A sun by date and time becomes the azimuth and elevation --sun gives.
  settings.daylight = resolveSunTime(settings.daylight, scene.site(), scene.directory());
  // A store camera by name becomes the job's camera, exactly as stored (its
  // cell too), and brings its image size unless the job gives one.
  const Camera* sizeFrom = &scene.camera();
  if (!settings.cameraName.empty()) {
    if (const std::string problem = cameraChoiceProblem(settings); !problem.empty())
      throw std::invalid_argument(problem);
    const Camera& named = namedCamera(settings.cameraName, scene);
    settings.camera = jobCameraOf(named);
    settings.cameraName.clear();
    sizeFrom = &named;
  }
  if (settings.analysis) {
    // Its film: a row per sensor (common/analysis/sensor_film.h).
    settings.width = kSensorFilmColumns;
    settings.height = settings.analysis->sensors;
  } else if (settings.width == 0 || settings.height == 0) {
    settings.width = sizeFrom->width;
    settings.height = sizeFrom->height;
  }
  if (settings.accel.empty()) settings.accel = defaults.accel;
  // Render leases may build another structure: they trace many rays per
  // triangle, where one that costs more to build and less to trace pays.
  if (settings.renderAccel.empty())
    settings.renderAccel = settings.accel == "grid" || settings.accel == "auto" ? "bvh" : settings.accel;
  if (settings.lightHops == kAutomaticLightHops) {
    // Lights a couple of rooms away matter; a couple of voxels away is no
    // distance at all: voxel cells sample every light.
    settings.lightHops = hasVoxelCells(scene) ? -1 : 2;
  }
  // A cell or portal picture has no photon pass: its 0 stays 0.
  if (settings.photons == 0 && settings.aov == JobSettings::Aov::Radiance)
    settings.photons = defaultPhotonCount(scene.lights().size());
  if (settings.photonK == 0) settings.photonK = defaults.photonK;
  if (settings.exposure == 0) settings.exposure = defaults.exposure;
  settings.camera = resolveCamera(settings.camera, scene);
  if (settings.maxPasses == 0) settings.maxPasses = settings.progressive() ? kProgressiveMaxPasses : 1;
  return settings;
}

void validateJobSettings(const JobSettings& settings, const SceneStore& scene) {
  if (const std::string problem = daylightProblem(settings.daylight); !problem.empty())
    throw std::invalid_argument(problem);
  if (settings.daylight.any() && daylightOpenings(scene).empty())
    throw std::invalid_argument(fmt::format("scene {} has no opening to the outside for --sun or --sky: no portal "
                                            "joins a cell to one named outside, sky, outside-*, sky-* or facade-*",
                                            scene.directory()));
  if (scene.lights().empty() && !settings.daylight.any())
    throw std::invalid_argument(fmt::format("scene {} has no lights (and the job no --sun or --sky)", scene.directory()));
  if (const std::string problem = luminanceProblem(settings); !problem.empty()) throw std::invalid_argument(problem);
  if (settings.analysis) validateAnalysis(settings);
  else {
    requireAtMost("image width", settings.width, limits::kMaxImageSide);
    requireAtMost("image height", settings.height, limits::kMaxImageSide);
  }
  const uint64_t pixels = uint64_t(settings.width) * settings.height;
  if (pixels > limits::kMaxImagePixels)
    throw std::invalid_argument(fmt::format("image {}x{} is too large: at most {} pixels", settings.width,
                                            settings.height, limits::kMaxImagePixels));
  if (settings.spp == 0 || settings.spp > limits::kMaxSpp)
    throw std::invalid_argument(fmt::format("spp {} must be between 1 and {}", settings.spp, limits::kMaxSpp));
  if (!settings.analysis && pixels * settings.spp > limits::kMaxCameraSamples)
    throw std::invalid_argument(fmt::format("{}x{} pixels at {} spp is too many camera samples: at most {}",
                                            settings.width, settings.height, settings.spp,
                                            limits::kMaxCameraSamples));
  if (settings.photons == 0 && settings.aov == JobSettings::Aov::Radiance)
    throw std::invalid_argument("photons must be at least 1");
  requireAtMost("photons", settings.photons, limits::kMaxPhotons);
  requireAtMost("gather rays", settings.gather, limits::kMaxGather);
  requireAtMost("light samples", settings.lightSamples, limits::kMaxLightSamples);
  requireAtMost("photon k", settings.photonK, limits::kMaxPhotonK);
  if (!(settings.photonRadius > 0) || !(settings.photonRadius <= limits::kMaxPhotonRadius))
    throw std::invalid_argument(fmt::format("photon radius {} must be a number above 0 and at most {} m",
                                            settings.photonRadius, limits::kMaxPhotonRadius));
  if (settings.lightHops < -1 || settings.lightHops > limits::kMaxLightHops)
    throw std::invalid_argument(fmt::format("light hops {} must be -2 (automatic), -1 (every light) or 0 to {}",
                                            settings.lightHops, limits::kMaxLightHops));
  if (!(settings.exposure >= limits::kMinExposure && settings.exposure <= limits::kMaxExposure))
    throw std::invalid_argument(fmt::format("exposure {} must be a number from {:g} to {:g}", settings.exposure,
                                            limits::kMinExposure, limits::kMaxExposure));
  validateRenderPasses(settings);
  // A bad --accel is refused here, naming the problem, rather than failing
  // every cell's lease in the workers.
  validateAcceleratorSpec(parseAcceleratorSpec(settings.accel));
  validateAcceleratorSpec(parseAcceleratorSpec(settings.renderAccel));
  const uint32_t cameraCell = settings.camera ? settings.camera->cell : scene.camera().cell;
  if (cameraCell >= scene.cells().size())
    throw std::invalid_argument(fmt::format("scene {}: the camera's cell {} does not exist", scene.directory(),
                                            cameraCell));
  checkPortalsPerCell(scene);
}

void queuePhotonEmission(JobStore& store, uint64_t job, wire::JobSpec::Reader spec, const SceneStore& scene,
                         const std::atomic<bool>* stop) {
  // The cell and portal pictures need no light: the photon phase is empty.
  if (spec.getAov() != wire::Aov::RADIANCE) return;
  // The scene's lights, then the daylight's emitters (light ids on from
  // the scene's light count: CellKernel::emitPhotons). A daylight-factor
  // job's lamps are off (lampsLit): no photons, their ids kept.
  const JobSettings settings = jobSettingsFromWire(spec);
  std::vector<Vec3> powers;
  std::vector<uint32_t> cells;
  for (const AreaLight& light : scene.lights()) {
    powers.push_back(lampsLit(settings) ? light.power() : Vec3(0.0f));
    cells.push_back(light.cell);
  }
  if (spec.hasDaylight()) {
    const DaylightEmitters daylight(scene, settings.daylight);
    for (size_t e = 0; e < daylight.count(); ++e) {
      powers.push_back(daylight.power(e));
      cells.push_back(daylight.cell(e));
    }
  }
  const std::vector<uint64_t> share = photonSharesOfPowers(powers, spec.getPhotons());

  // Past a billion photons the batches grow, so that a job is at most
  // ~kMostEmitBatches rows (queued in about a second): a photon's path
  // depends on its id alone, so how they are cut into batches changes no bit.
  const uint64_t perBatch =
      std::max<uint64_t>(kPhotonsPerEmitBatch, (spec.getPhotons() + kMostEmitBatches - 1) / kMostEmitBatches);
  uint64_t nextPath = 0;
  for (size_t i = 0; i < powers.size(); ++i) {
    for (uint64_t first = 0; first < share[i]; first += perBatch) {
      if (stop && stop->load(std::memory_order_relaxed))
        throw std::runtime_error("the coordinator is stopping: job not queued");
      const uint32_t count = static_cast<uint32_t>(std::min<uint64_t>(perBatch, share[i] - first));
      capnp::MallocMessageBuilder message;
      auto emit = message.initRoot<wire::RayBatch>().initEmit();
      emit.setLight(static_cast<uint32_t>(i));
      emit.setFirstPath(nextPath + first);
      emit.setCount(count);
      emit.setPhotonsOfLight(share[i]);
      store.addBatch(job, cells[i], 0, BatchKind::Emit, count, net::packToString(message));
    }
    nextPath += share[i];
  }
}

void queueCameraRays(JobStore& store, uint64_t job, wire::JobSpec::Reader spec, const SceneStore& scene) {
  // An analysis job's "pixels" are its sensors, queued by the cells they lie in.
  if (spec.hasAnalysis()) {
    queueSensors(store, job, spec, decodeSensors(store.jobSensors(job), scene));
    return;
  }
  const uint32_t pixels = spec.getWidth() * spec.getHeight();
  // A resolved spec always has its camera; one stored without it renders the store's.
  const uint32_t cameraCell = spec.hasCamera() ? spec.getCamera().getCell() : scene.camera().cell;
  const uint32_t pixelsPerBatch = std::max<uint32_t>(1, kSamplesPerCameraBatch / spec.getSpp());
  for (uint32_t first = 0; first < pixels; first += pixelsPerBatch) {
    const uint32_t count = std::min(pixelsPerBatch, pixels - first);
    capnp::MallocMessageBuilder message;
    auto camera = message.initRoot<wire::RayBatch>().initCamera();
    camera.setFirstPixel(first);
    camera.setPixelCount(count);
    store.addBatch(job, cameraCell, 1, BatchKind::Camera, int64_t(count) * spec.getSpp(),
                   net::packToString(message));
  }
}

}  // namespace portico
