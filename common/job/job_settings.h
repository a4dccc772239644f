// A job's settings: what it computes, with the one set of defaults there
// is. The `render` and `submit` options bind to these fields, the submit
// message carries them (common/net/job_spec_wire.h), the coordinator
// resolves every automatic value once at submit (resolveJobSettings,
// coordinator/job_planner.h) and stores the result, and workers trace with
// that complete spec.
#pragma once

#include <algorithm>
#include <cstdint>
#include <optional>
#include <string>

#include "common/math.h"

namespace portico {

// lightHops meaning "choose from the store": 2 for room cells, all lights
// for voxel cells (scene import --grid).
constexpr int kAutomaticLightHops = -2;

// How a shading point chooses among its candidate lights
// (common/transport/light_sampler.h): one descent of a light tree, or a
// scan weighing every candidate (the way before the tree, kept to compare).
enum class LightSampling : uint8_t { Tree, Scan };

// Render passes at most of a job with a target error or a time limit and no
// --max-passes: a bound for a target never reached (64 passes of the
// default 16 spp are 1024 samples per pixel).
constexpr uint32_t kProgressiveMaxPasses = 64;

// A job's own camera, chosen at render time (`--look-from`, `--look-at`,
// `--up`, `--fov`): photon maps do not depend on it. A zero up or fov means
// the store camera's; resolveJobSettings fills them and the cell.
struct JobCamera {
  Vec3 lookFrom, lookAt, up{0, 0, 0};
  float fovYDegrees = 0;
  uint32_t cell = 0;                 // the cell containing lookFrom
  bool operator==(const JobCamera&) const = default;
};

// A sun by date, time and place (`--sun-time`, `--latitude`, `--longitude`,
// `--north-azimuth`): in a submit only. The coordinator resolves it into
// the sun's azimuth and elevation (resolveSunTime, common/job/sun_time.h),
// with the store's site where the job gives no place, and clears it: the
// stored job is the one `--sun AZ,EL` makes.
struct SunTime {
  int64_t unixSeconds = 0;                   // the instant, POSIX seconds (UTC)
  std::optional<double> latitudeDegrees;     // unset: the store's site
  std::optional<double> longitudeDegrees;
  std::optional<double> northAzimuthDegrees; // unset: the store's site's, else 0
  bool operator==(const SunTime&) const = default;
};

// Daylight (docs/daylight.md): a sky and a sun outside the building, whose
// light enters through the portals into outdoor cells. Radiance and
// irradiance are per RGB channel in the units of lamps' radiance
// (W m^-2 sr^-1); luminance = 179 lm/W times their Rec. 709 Y.
struct DaylightSettings {
  enum class Sky : uint8_t { None, Uniform, Preetham, Overcast } sky = Sky::None;
  Vec3 skyRadiance;                  // Uniform: the radiance of every direction
  float turbidity = 3.0f;            // Preetham's sky and the sun's colour and strength
  bool sun = false;
  // Azimuth from +Z towards +X, elevation above the horizontal (+Y up).
  float sunAzimuthDegrees = 0, sunElevationDegrees = 0;
  std::optional<SunTime> sunTime;    // set: the angles above are to be resolved from it
  Vec3 sunIrradiance;                // on a plane facing the sun; zero: the sun model's
  bool any() const { return sun || sky != Sky::None; }
  bool operator==(const DaylightSettings&) const = default;
};

// A lighting analysis (docs/lighting-analysis.md): the job measures the
// illuminance at sensors instead of rendering an image. Its sensors travel
// beside the settings (wire::Submit.sensors), kept by the coordinator.
struct AnalysisSettings {
  uint32_t sensors = 0;              // how many
  bool daylightFactor = false;       // under the CIE overcast sky: DF = 100 E / E_out per sensor
  bool operator==(const AnalysisSettings&) const = default;
};

// A render's image in photometric units (`--aov luminance`,
// docs/lighting-reports.md): each pixel's luminance in cd/m^2, 179 lm/W x
// the Rec. 709 Y of its radiance, written as a float image; with
// `--falsecolor`, also OUTPUT.falsecolor.png, the luminance on a false-colour
// scale with its legend, as Radiance's `falsecolor` draws it. The light
// traced is the radiance render's, bit for bit: only the image written differs.
struct LuminanceImage {
  bool falseColor = false;
  double falseColorMaximum = 0;   // cd/m^2 at the scale's top (red); 0: the 95th percentile, rounded up
  uint32_t falseColorDecades = 0; // 0: a linear scale from 0; N: logarithmic over N decades below the top
  uint32_t falseColorSteps = 8;   // legend intervals
  bool operator==(const LuminanceImage&) const = default;
};
// The bounds of its scale: beyond any sky, sun or lamp seen.
constexpr double kMaxFalseColorMaximum = 1e12;
constexpr uint32_t kMaxFalseColorDecades = 12;
constexpr uint32_t kMaxFalseColorSteps = 32;

// An analysis job's sampling by default (`portico analyze`): a sensor is
// one point, so it can take far more rays than a pixel. 64 samples of 4
// shadow rays and 16 gather rays: 256 shadow and 1 024 gather rays a sensor.
constexpr uint32_t kAnalysisSpp = 64;
constexpr uint32_t kAnalysisGather = 16;
constexpr uint32_t kAnalysisLightSamples = 4;

struct JobSettings {
  std::string store;                 // scene store directory (absolute once submitted)
  std::string output;                // image path (.png or .exr)
  // Per-cell accelerator of the photon pass. auto (each cell's structure
  // chosen by the cost model) is the fastest photon pass of grid, bvh and
  // auto on every preset of `portico bench pipeline`
  // (docs/pipeline-benchmark.md).
  std::string accel = "auto";
  // Render leases' structure; "" (automatic): bvh with grid or auto, else
  // the accel. Render rays are many per triangle: bvh traces camera rays
  // 1.3-1.9x as fast as kd:sah and builds 2.5x as fast
  // (docs/accelerator-benchmarks.md).
  std::string renderAccel;
  // Defaults checked against the reference scenes (docs/validation.md):
  // final gathering at every camera hit, multi-jittered pixel samples.
  // 0: chosen from the building at submit (defaultPhotonCount,
  // coordinator/job_planner.h): 5 000 per light, 400 000 to 20 M.
  uint64_t photons = 0;
  uint32_t spp = 16;
  uint32_t gather = 4;               // final-gather rays per camera hit (0: estimate at the hit)
  uint64_t seed = 1;
  uint32_t width = 0, height = 0;    // 0: the camera's
  // Shadow rays per camera hit. A pixel's light samples form one
  // stratified pattern (pixel_pattern.h): 16 spp of 1 cover a lamp as well
  // as 16 of 2 (the same block RMSE on both reference scenes), for ~10 %
  // less time.
  uint32_t lightSamples = 1;
  int lightHops = kAutomaticLightHops;   // sample lights of cells within this many portals (-1: all)
  LightSampling lightSampling = LightSampling::Tree;
  // Photons per density estimate: 128 rather than 64 lowers the reference
  // scenes' block RMSE (cornell_closed 0.91 -> 0.75 %, two_rooms 2.09 ->
  // 1.88 %) for ~10 % more render time (docs/image-quality.md).
  uint32_t photonK = 128;
  float photonRadius = 0.5f;         // largest search radius, metres
  float exposure = 1.0f;             // PNG exposure
  // What a gather hit reads: the nearest precomputed irradiance (Christensen;
  // IrradianceCache), or the k-nearest-photon estimate searched there.
  enum class Irradiance { Precomputed, Knn } irradiance = Irradiance::Precomputed;
  enum class Aov { Radiance, Cells, Portals } aov = Aov::Radiance;   // what the image shows
  // Unset: the store's camera; always set once resolved, so that every
  // worker traces the same camera rays.
  std::optional<JobCamera> camera;
  // Not what the job computes but how: a photon pass of its own rather than
  // an earlier job's finished one (`--fresh-photons`). Carried by the submit
  // message (wire::Submit.freshPhotons), not by the stored spec.
  bool freshPhotons = false;
  // Progressive rendering: the render phase runs passes of `spp` samples per
  // pixel, each with its own seed, and stops after the first pass whose
  // error estimate (relative standard error of 16x16 blocks, from the
  // passes' spread; at least 2 passes) is at most targetError, before a
  // pass predicted to end past timeLimitSeconds of render, or after
  // maxPasses passes. Unset and 0: one pass, today's image bit for bit.
  std::optional<double> targetError;
  std::optional<double> timeLimitSeconds;
  uint32_t maxPasses = 0;            // 0: 1 without a target or time limit, else kProgressiveMaxPasses
  bool progressive() const { return targetError || timeLimitSeconds; }
  // A store camera by name (`--camera NAME`; empty: none), instead of a
  // camera of the job's own. Resolved at submit into `camera` and cleared:
  // workers see only the resolved camera.
  std::string cameraName;
  DaylightSettings daylight;
  // Set: a lighting analysis, whose output is a CSV of its sensors' readings.
  std::optional<AnalysisSettings> analysis;
  // Set: the image is luminance in cd/m^2 (`--aov luminance`, `--falsecolor`).
  std::optional<LuminanceImage> luminance;

  // The renderer's own constants, the same for every job (not on the wire).
  uint32_t maxPhotonBounces = 64;
  // A precomputed point at about one photon in this many of a cell's map.
  uint32_t irradianceStride = 8;
  // Photons per precomputed estimate: each is read by many gather hits, so
  // it can use fewer than an estimate seen directly (as Jensen's gather
  // lookups do, §9.3.2); measured on the reference scenes, half of photonK
  // gives a lower block error than photonK, in less time.
  uint32_t irradianceK() const { return std::max(8u, photonK / 2); }

  bool operator==(const JobSettings&) const = default;
};

// Whether the scene's lamps (area lights, emissive objects, IES luminaires)
// light the job. A daylight-factor analysis is lit by the CIE overcast sky
// alone: DF = 100 E_in / E_out compares the sky's light indoors with the
// same sky's outdoors, and a lamp left on would count as daylight (an
// imported house's ceiling lamps read as DF of 100 % and more under them).
// Its lamps emit no photons, and no shadow ray is drawn to them.
inline bool lampsLit(const JobSettings& settings) { return !(settings.analysis && settings.analysis->daylightFactor); }

// Why the settings' camera choice cannot be taken ("" when it can): a store
// camera by name and a camera of the job's own both given.
std::string cameraChoiceProblem(const JobSettings& settings);

// Why the settings' luminance image cannot be made ("" when it can, or
// when the job makes none): an analysis, another aov, an output that cannot
// hold floats, a scale out of its bounds. The client asks before anything
// starts, the coordinator again at submit.
std::string luminanceProblem(const JobSettings& settings);

const char* toString(JobSettings::Irradiance irradiance);
const char* toString(LightSampling sampling);
const char* toString(JobSettings::Aov aov);

}  // namespace portico
