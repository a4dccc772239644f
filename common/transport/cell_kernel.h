// The light-transport work of one lease in one cell: expand generators
// (photon emission, camera rays), trace every ray until it ends here or
// crosses a portal, and collect deposits, crossings and film contributions.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <map>
#include <optional>
#include <stdexcept>
#include <vector>

#include "common/job/job_settings.h"
#include "common/scene/store/scene_store.h"
#include "common/transport/camera_model.h"
#include "common/transport/cell_tracer.h"
#include "common/transport/daylight_openings.h"
#include "common/transport/emitter_pixels.h"
#include "common/transport/film.h"
#include "common/transport/light_sampler.h"
#include "common/transport/outdoor_passage.h"
#include "common/transport/pixel_samples.h"
#include "common/transport/indirect_light.h"
#include "common/transport/photon_record.h"
#include "common/transport/pixel_pattern.h"
#include "common/transport/ray_state.h"
#include "common/transport/trace_counters.h"

namespace portico {

// Tracing given up midway: the kernel's stop flag was set (the lease's job
// was cancelled, or the worker is stopping).
struct TracingStopped : std::runtime_error {
  TracingStopped() : std::runtime_error("tracing stopped") {}
};

// False colours for the cell and portal pictures: distinct, stable hues.
Vec3 cellColour(uint32_t cell);
Vec3 portalCountColour(uint32_t crossings);

struct KernelOutputs {
  // By the cell whose table receives them: the cell traced, and neighbours
  // for photons within the photon radius of their shared portal. Encoded
  // as they are stored (16 bytes, not a StoredPhoton's 48): the Result
  // takes each table with one copy.
  std::map<uint32_t, std::vector<PhotonRecord>> deposits;
  std::map<uint32_t, std::vector<RayState>> crossings;   // by destination cell
  FilmAccumulator film;
  TraceCounters counters;
};

// An analysis job's sensor as a lease measures it (wire::SensorPoint):
// its row of the film, its point and the unit normal of its plane.
struct SensorTask {
  uint32_t index = 0;
  Vec3 position, direction;
};

class CellKernel {
 public:
  // indirect: the cell's photon map in the render phase (null in the photon
  // phase): every photon when final gathering, else only those that
  // bounced; with its irradiance cache when gather hits read one.
  CellKernel(const SceneStore& scene, const CellTracer& tracer, const JobSettings& parameters,
             const IndirectLight* indirect);

  // Lights from scene.lights().size() on are the daylight's emitters
  // (DaylightEmitters), in the order of their photon shares.
  void emitPhotons(uint32_t light, uint64_t firstPath, uint32_t count, uint64_t photonsOfLight, KernelOutputs& out);
  // Whether `light` (as emitPhotons numbers them) emits in this cell.
  bool emitsHere(uint32_t light) const;
  void generateCameraRays(uint32_t firstPixel, uint32_t pixelCount, KernelOutputs& out);
  // An analysis job's sensors, each lit as a camera hit on a white
  // Lambertian surface at its point facing its direction, whose light is
  // its irradiance (sensor_measure.cpp; film layout: sensor_film.h).
  void measureSensors(const std::vector<SensorTask>& sensors, KernelOutputs& out);
  // Runs a ray, and the shadow rays it spawns here, to its end in this cell or a crossing.
  void trace(const RayState& ray, KernelOutputs& out);
  // Final-gather hits that read the irradiance cache wait in the kernel
  // (see PendingGather); this reads them all and adds their light to `out`.
  // Call it after the last ray or camera batch a kernel traces.
  void finishGathers(KernelOutputs& out);
  // Checked before each photon, camera sample and traced ray (a camera
  // sample's gather rays take milliseconds): once set, tracing throws
  // TracingStopped. Each ray's output depends on the ray alone, so where
  // the checks fall changes no bit of what is traced.
  void setStopFlag(const std::atomic<bool>* stop) { stop_ = stop; }
  // Counted up at each of those checks: the worker's heartbeats carry it,
  // so that the coordinator tells a lease that traces from a stuck one.
  void setProgressCounter(std::atomic<uint64_t>* progress) { progress_ = progress; }

 private:
  void checkStop() const {
    if (progress_) progress_->fetch_add(1, std::memory_order_relaxed);
    if (stop_ && stop_->load(std::memory_order_relaxed)) throw TracingStopped();
  }
  void tracePhoton(RayState photon, KernelOutputs& out);
  // A daylight photon starts on its opening if nothing outdoors stands in
  // its way back to the sky: at once when the way crosses no geometry,
  // else after its probe (RayState::toSky) has gone out and found the sky.
  void emitDaylightPhoton(size_t emitter, uint64_t photonsOfEmitter, uint64_t path, KernelOutputs& out);
  void traceSkyProbe(const RayState& probe, KernelOutputs& out);
  // A ray towards the sky left the building with nothing in its way: a
  // shadow ray adds its light, a probe starts its photon.
  void reachSky(const RayState& ray, KernelOutputs& out);
  // A pixel's light is emitted light seen directly plus light reflected
  // towards the camera. Emitted light met inside the camera's own cell (a
  // lamp, the sky out of it) is estimated by emission rays of its own
  // (emissionSamplesPerPixel a pixel), which add only that; the shaded
  // samples (spp) add reflected light and the emitted light met beyond a
  // portal. Emission rays cost one traversal of one cell and no shading,
  // so many of them cover the edges of a bright lamp finely, where the
  // shaded samples' few positions would leave its pixels' coverage noisy;
  // ending them at the cell's portals keeps them cheap where most camera
  // rays cross many cells (an overview of a building).
  uint32_t emissionSamplesPerPixel() const;
  bool cellHasEmitters() const;
  void traceEmissionRays(uint32_t pixel, uint32_t count, std::vector<PixelSample>& samples,
                         std::vector<uint32_t>& scratch, KernelOutputs& out);
  // Emission rays carry kEmissionPath in their path id (shaded samples'
  // ids are pixel * spp + sample, far below it).
  static constexpr uint64_t kEmissionPath = 1ull << 63;
  static constexpr uint64_t kEmissionSeedSalt = 0x2545f4914f6cdd1dull;
  // Whether this camera ray adds the emitted light it meets: the two
  // estimates split the emitted light by where it is met, so each adds
  // its own share and none is counted twice.
  static bool emissionSeenByThisRay(const RayState& ray) { return isEmissionRay(ray) || ray.depth > 0; }
  static bool isEmissionRay(const RayState& ray) {
    return ray.kind == RayKind::Camera && (ray.pathId & kEmissionPath) != 0;
  }
  void addEmission(const RayState& ray, const CellEvent& hit, KernelOutputs& out);
  // A camera ray meeting a luminaire's luminous opening (openingsHere_)
  // before `end` ends there: the opening is opaque to the camera, and
  // shows its luminance I / A_projected (its emitted light: the ray's
  // share, as addEmission's). Returns whether it met one.
  bool seeLuminaire(const RayState& ray, float end, KernelOutputs& out);
  // A camera ray traced on from just before a portal (tMinBeforePortal)
  // can hit a wall a hair beyond the cell's box; a gather or shadow ray
  // starting there, outside the box, would leave the cell without meeting
  // the portal. Such an origin is moved a hair inside (never a point
  // already inside).
  Vec3 insideCell(const Vec3& point) const;
  void traceCameraRay(const RayState& ray, KernelOutputs& out);
  // Traces `ray` through the glass panes in its way (at most
  // kMaxGlassEvents): a shadow ray keeps its line, weighed by each pane's
  // transmittance; any other ray passes or reflects at random
  // (passOrReflect). Returns the first event that is not a pane.
  CellEvent traceThroughGlass(RayState& ray, KernelOutputs& out) const;
  void traceShadowRay(const RayState& ray, KernelOutputs& out);
  void traceGatherRay(const RayState& ray, KernelOutputs& out);
  void deposit(const StoredPhoton& photon, KernelOutputs& out);
  void addToFilm(uint32_t pixel, const Vec3& radiance, KernelOutputs& out);
  void shade(const RayState& ray, const CellEvent& hit, KernelOutputs& out);
  void cross(RayState ray, const CellEvent& event, KernelOutputs& out);
  // A camera hit's lightSamples shadow rays, drawn from its pixel's patterns.
  void sampleLights(const RayState& ray, const Vec3& point, const Vec3& normal, const Vec3& brdf, KernelOutputs& out);
  // One shadow ray, to the lamp `choice` picks, at `onLight` on it; its
  // light is divided by `samples`.
  void sampleLight(const RayState& ray, const Vec3& point, const Vec3& normal, const Vec3& brdf, float choice,
                   const PatternPoint& onLight, uint32_t samples, KernelOutputs& out);
  // The shadow ray to point luminaire `light`, chosen with `probability`
  // (times the samples its light is divided by).
  void samplePointLight(const RayState& ray, const Vec3& point, const Vec3& normal, const Vec3& brdf,
                        const AreaLight& light, float probability, KernelOutputs& out);
  // (u, v): the point on the sun's disc.
  void sampleSun(const RayState& ray, const Vec3& point, const Vec3& normal, const Vec3& brdf, float u, float v,
                 KernelOutputs& out);
  // toSky: the light is the sky beyond the opening at `distance`.
  void addShadowRay(const RayState& ray, const Vec3& origin, const Vec3& direction, float distance,
                    const Vec3& contribution, bool toSky, KernelOutputs& out);
  // A ray reaching a glass pane: reflected (true: `ray` is the mirrored
  // ray) or passed through (`ray` continues beyond the pane), chosen at
  // random in proportion to the pane's reflectance, with its weight times
  // the tint when it passes.
  bool passOrReflect(RayState& ray, const CellEvent& hit, const Material& glass) const;
  const Material& materialAt(uint32_t primitive) const {
    return scene_.materials()[tracer_.cell().material(primitive)];
  }

  // A gather hit waiting for its irradiance lookup. Lookups made one after
  // another at random places of the cell each miss the caches and mispredict
  // the tree's branches; made in the order of a coarse grid over the cell
  // (counting sort on 16^3 blocks), consecutive ones read the same leaves.
  // The film's sums do not depend on the order contributions arrive in
  // (film.h), so no bit changes.
  struct PendingGather {
    Vec3 point, normal, weight, albedo;
    uint64_t pathId;
    uint32_t pixel;
    uint32_t key;       // of the gather ray's state (gatherKey): a short hit's random numbers
    float distance;     // from the gather ray's origin to the hit
    bool secondary;     // a short gather's own gather ray: read wherever it lands
  };
  // Waiting hits are read when this many are held, to bound the memory.
  static constexpr size_t kMaxPendingGathers = size_t{1} << 16;
  void readGather(const PendingGather& gather, KernelOutputs& out);
  void readPendingGathers(KernelOutputs& out);
  std::vector<PendingGather> pendingGathers_;

  // A short gather ray (Jensen 2001, section 9.3.3): one that lands closer
  // to its origin than kShortGatherRadii times the radius of the photon disc
  // its estimate there averages over. Seen from so near, the estimate's
  // blur is not averaged away by the gather: where a box stands on the
  // floor, the floor's estimate spreads the lit floor's light into the
  // box's shadow by its base, and the box's face reads that from close by
  // (+1 to +2 % on its lower blocks in cornell_closed); where a wall meets
  // the floor, part of each disc lies beyond the other surface (-2 %).
  // Such a hit takes no estimate: its light is computed as a camera hit's
  // is, direct light by a shadow ray and indirect light by one gather ray
  // of its own, which reads the estimate wherever it lands (its `secondary`
  // mark, carried across portals in the depth's kSecondaryGatherDepth bit
  // (ray_state.h), stops any further recursion). Short hits wait until the pending
  // lookups are read (traceShortGathers), as those do. 6 radii: 5.7 % of
  // cornell_closed's gather rays, block RMSE 0.42 -> 0.31 % (2 radii:
  // 1.9 %, 0.39 %; 8: 8.7 %, 0.30 %).
  static constexpr float kShortGatherRadii = 6.0f;
  void traceShortGathers(KernelOutputs& out);
  void traceShortGather(const PendingGather& gather, KernelOutputs& out);
  std::vector<PendingGather> shortGathers_;

  const SceneStore& scene_;
  const CellTracer& tracer_;
  const JobSettings& parameters_;
  // The lattice of this cell's photon table, made once: every deposit is
  // encoded on it (copies across portals on their neighbour's).
  const PhotonFrame ownFrame_;
  const PhotonMap* photons_;
  const IrradianceCache* irradiance_;
  // Daylight's emitters, when the job has daylight.
  std::optional<DaylightEmitters> daylight_;
  std::optional<OutdoorPassage> outdoors_;
  // The scene's lights, then one per daylight opening (the sky seen
  // through it) for the light sampler; openings of cells within the
  // light hops are its candidates, and the sun's.
  std::vector<AreaLight> lights_;
  std::vector<uint32_t> nearOpenings_;
  // Luminaires whose luminous opening reaches into this cell's box (lamps
  // lit): a camera ray in the cell may see them. An opening across a cell
  // boundary is in each cell's list; a ray, traced cell after cell along
  // its line, meets it in the one where its line does.
  std::vector<uint32_t> openingsHere_;
  std::vector<Bounds3> openingBoxes_;
  std::optional<LightSampler> lightSampler_;
  std::optional<CameraModel> camera_;
  // Where emission rays can meet an emitter, made by the first camera batch
  // that traces them (none with daylight: the sky shows through openings).
  std::optional<EmitterPixels> emitterPixels_;
  const std::atomic<bool>* stop_ = nullptr;
  std::atomic<uint64_t>* progress_ = nullptr;
};

}  // namespace portico
