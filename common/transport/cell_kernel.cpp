#include "common/transport/cell_kernel.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "common/rng.h"
#include "common/transport/albedo_texture.h"
#include "common/transport/photon_power_unit.h"
#include "common/transport/photon_scattering.h"
#include "common/transport/pixel_pattern.h"
#include "common/transport/pixel_samples.h"
#include "common/transport/sampling.h"
#include "common/transport/sun_disc.h"
#include "common/transport/surface_point.h"
#include "common/transport/thin_glass.h"

namespace portico {

namespace {
Vec3 hitNormalFacing(const MeshView& mesh, uint32_t primitive, const Vec3& direction, bool& frontFacing) {
  const Vec3 n = normalize(mesh.geometricNormal(primitive));
  frontFacing = dot(n, direction) < 0;
  return frontFacing ? n : -n;
}

Ray toRay(const RayState& state) { return {state.origin, state.direction, state.tMin, state.tMax}; }

// The job's camera (resolved at submit, the same for every worker); the
// store's for settings that carry none.
Camera cameraOf(const JobSettings& parameters, const SceneStore& scene) {
  Camera camera = scene.camera();
  if (const auto& chosen = parameters.camera) {
    camera.origin = chosen->lookFrom;
    camera.target = chosen->lookAt;
    camera.up = chosen->up;
    camera.fovYDegrees = chosen->fovYDegrees;
    camera.cell = chosen->cell;
  }
  return camera;
}

// Glass panes a ray meets in one cell at most: past them it ends (a photon
// is absorbed, a shadow ray blocked).
constexpr int kMaxGlassEvents = 16;

// A key of the ray's exact state: rays of one path (a pixel sample's gather
// rays) differ in it, and it is the same wherever the ray is traced. Each
// use salts it with its own constant.
uint32_t stateKey(const RayState& ray, uint64_t salt) {
  uint64_t h = mix64(ray.pathId ^ salt);
  for (float f : {ray.origin.x, ray.origin.y, ray.origin.z, ray.direction.x, ray.direction.y, ray.direction.z,
                  ray.tMin}) {
    uint32_t bits;
    std::memcpy(&bits, &f, sizeof bits);
    h = mix64(h ^ bits);
  }
  return static_cast<uint32_t>(h);
}

// The key of the random choice at a glass pane.
uint32_t glassKey(const RayState& ray) { return stateKey(ray, 0x6a09e667f3bcc909ull); }
// The key of a short gather hit's random numbers (CellKernel::traceShortGather).
uint32_t gatherKey(const RayState& ray) { return stateKey(ray, 0xbb67ae8584caa73bull); }
}  // namespace

CellKernel::CellKernel(const SceneStore& scene, const CellTracer& tracer, const JobSettings& parameters,
                       const IndirectLight* indirect)
    : scene_(scene),
      tracer_(tracer),
      parameters_(parameters),
      ownFrame_(scene.cells()[tracer.cell().id()].bounds, parameters.photonRadius, photonPowerUnit(scene, parameters)),
      photons_(indirect ? &indirect->photons : nullptr),
      irradiance_(indirect && indirect->irradiance ? &*indirect->irradiance : nullptr),
      lights_(scene.lights()) {
  if (parameters.width && parameters.height) camera_.emplace(cameraOf(parameters, scene), parameters.width, parameters.height);
  // A daylight-factor analysis samples the sky's openings only (lampsLit).
  std::vector<uint32_t> candidates;
  if (lampsLit(parameters)) candidates = LightSampler::lightsNear(scene, tracer.cell().id(), parameters.lightHops);
  if (lampsLit(parameters)) {
    const Bounds3& box = scene.cells()[tracer.cell().id()].bounds;
    for (const AreaLight& light : scene.lights()) {
      const Bounds3 opening = light.openingBounds();
      if (opening.empty() || opening.lo.x > box.hi.x || opening.lo.y > box.hi.y || opening.lo.z > box.hi.z ||
          opening.hi.x < box.lo.x || opening.hi.y < box.lo.y || opening.hi.z < box.lo.z)
        continue;
      openingsHere_.push_back(light.id);
      openingBoxes_.push_back(opening);
    }
  }
  if (parameters.daylight.any()) {
    daylight_.emplace(scene, parameters.daylight);
    outdoors_.emplace(scene);
    const std::vector<bool> near = LightSampler::cellsNear(scene, tracer.cell().id(), parameters.lightHops);
    for (const AreaLight& opening : daylight_->openings()) {
      AreaLight light = opening;
      light.id = static_cast<uint32_t>(lights_.size());
      if (opening.cell < near.size() && near[opening.cell]) {
        nearOpenings_.push_back(opening.id);
        // Sampled in proportion to the sky's power through it.
        if (daylight_->sky().hasSky()) {
          light.radiance = daylight_->sky().irradianceFacing(-opening.normal()) / kPi;
          if (maxComponent(light.radiance) > 0) candidates.push_back(light.id);
        }
      }
      lights_.push_back(light);
    }
  }
  lightSampler_.emplace(lights_, std::move(candidates), parameters.lightSampling);
}

bool CellKernel::emitsHere(uint32_t light) const {
  const size_t sceneLights = scene_.lights().size();
  const uint32_t cell = tracer_.cell().id();
  if (light < sceneLights) return scene_.lights()[light].cell == cell;
  return daylight_ && light - sceneLights < daylight_->count() && daylight_->cell(light - sceneLights) == cell;
}

void CellKernel::emitPhotons(uint32_t lightId, uint64_t firstPath, uint32_t count, uint64_t photonsOfLight,
                             KernelOutputs& out) {
  if (lightId >= scene_.lights().size()) {
    const size_t emitter = lightId - scene_.lights().size();
    if (!daylight_ || emitter >= daylight_->count())
      throw std::invalid_argument("an emission batch names light " + std::to_string(lightId) + ", which the job lacks");
    for (uint64_t path = firstPath; path < firstPath + count; ++path) {
      checkStop();
      emitDaylightPhoton(emitter, photonsOfLight, path, out);
    }
    return;
  }
  if (!lampsLit(parameters_))
    throw std::invalid_argument("an emission batch names lamp " + std::to_string(lightId) +
                                " of a daylight-factor job, whose lamps are off");
  const AreaLight& light = scene_.lights().at(lightId);
  const Vec3 normal = light.normal();
  const Vec3 power = light.power() / float(photonsOfLight);
  for (uint64_t path = firstPath; path < firstPath + count; ++path) {
    checkStop();
    const RayState photon = emitPhoton(light, normal, power, parameters_.seed, path);
    ++out.counters.photonsEmitted;
    tracePhoton(photon, out);
  }
}

void CellKernel::generateCameraRays(uint32_t firstPixel, uint32_t pixelCount, KernelOutputs& out) {
  if (!camera_) throw std::logic_error("camera rays need the image size");
  const uint32_t spp = parameters_.spp;
  const Vec3 weight(1.0f / float(spp));
  std::vector<PixelSample> samples;
  std::vector<uint32_t> scratch;
  const uint32_t emissionSpp = emissionSamplesPerPixel();
  if (emissionSpp > 0 && !daylight_ && !emitterPixels_)
    emitterPixels_.emplace(*camera_, parameters_.width, parameters_.height, tracer_.cell(), scene_.materials(),
                           openingBoxes_);
  for (uint32_t pixel = firstPixel; pixel < firstPixel + pixelCount; ++pixel) {
    traceEmissionRays(pixel, emissionSpp, samples, scratch, out);
    const uint32_t x = pixel % parameters_.width, y = pixel / parameters_.width;
    // Box filter, correlated multi-jittered positions (pixel_samples.h).
    pixelSamples(parameters_.seed, pixel, spp, samples, scratch);
    for (uint32_t sample = 0; sample < spp; ++sample) {
      checkStop();
      RayState ray;
      ray.kind = RayKind::Camera;
      ray.pathId = uint64_t(pixel) * spp + sample;
      ray.pixel = pixel;
      const float px = float(x) + samples[sample].x;
      const float py = float(y) + samples[sample].y;
      ray.origin = camera_->origin();
      ray.direction = camera_->direction(px, py);
      ray.weight = weight;
      ++out.counters.cameraRays;
      traceCameraRay(ray, out);
    }
  }
}

bool CellKernel::cellHasEmitters() const {
  if (!openingsHere_.empty()) return true;
  const CellGeometry& cell = tracer_.cell();
  for (uint32_t primitive = 0; primitive < cell.mesh().triangleCount; ++primitive)
    if (scene_.materials()[cell.material(primitive)].emissive()) return true;
  return false;
}

uint32_t CellKernel::emissionSamplesPerPixel() const {
  if (parameters_.aov != JobSettings::Aov::Radiance) return 0;
  // They see only what is emitted inside this cell (or the sky out of it):
  // with no emitter here and no daylight they would all add zero.
  if (!daylight_ && !cellHasEmitters()) return 0;
  // An 8 x 8 multi-jittered pattern (64) takes a lamp's edge in
  // cornell_closed from +-2.6 % (16) to under 1.2 % of its 16 x 16 block at
  // 16 spp, a 16 x 16 one (256) to under 0.5 %.
  // With daylight they are traced in every pixel (the sky may show through
  // any opening): 64 a pixel. Without, only in the few pixels where a lamp
  // may show (emitter_pixels.h), so 256 cost little (cornell_closed: 248 000
  // rays, against 4.2 M gather rays) and take its lamp's edge blocks from
  // -1.2 / +1.0 % to -0.4 / +0.2 % (docs/image-quality.md).
  if (daylight_) return std::max(64u, 4 * parameters_.spp);
  return std::max(256u, 16 * parameters_.spp);
}

void CellKernel::traceEmissionRays(uint32_t pixel, uint32_t count, std::vector<PixelSample>& samples,
                                   std::vector<uint32_t>& scratch, KernelOutputs& out) {
  if (count == 0) return;
  // All would miss the cell's emitters and add nothing.
  if (emitterPixels_ && !emitterPixels_->mayShowEmitter(pixel)) return;
  const uint32_t x = pixel % parameters_.width, y = pixel / parameters_.width;
  // Positions of their own, not those of the shaded samples.
  pixelSamples(mix64(parameters_.seed ^ kEmissionSeedSalt), pixel, count, samples, scratch);
  const Vec3 weight(1.0f / float(count));
  for (uint32_t sample = 0; sample < count; ++sample) {
    RayState ray;
    ray.kind = RayKind::Camera;
    ray.pathId = kEmissionPath | (uint64_t(pixel) * count + sample);
    ray.pixel = pixel;
    ray.origin = camera_->origin();
    ray.direction = camera_->direction(float(x) + samples[sample].x, float(y) + samples[sample].y);
    ray.weight = weight;
    ++out.counters.emissionRays;
    traceCameraRay(ray, out);
  }
}

void CellKernel::trace(const RayState& ray, KernelOutputs& out) {
  checkStop();
  if (!isValid(ray)) {
    ++out.counters.raysInvalid;
    return;
  }
  switch (ray.kind) {
    case RayKind::Photon:
      if (ray.toSky)
        traceSkyProbe(ray, out);
      else
        tracePhoton(ray, out);
      break;
    case RayKind::Camera: traceCameraRay(ray, out); break;
    case RayKind::Shadow: traceShadowRay(ray, out); break;
    case RayKind::Gather: traceGatherRay(ray, out); break;
  }
}

Vec3 cellColour(uint32_t cell) {
  // Golden-ratio hue steps keep neighbouring ids apart; value and saturation
  // vary a little too, so that hundreds of cells stay distinguishable.
  const float hue = std::fmod(0.13f + cell * 0.61803398875f, 1.0f);
  const float saturation = 0.55f + 0.35f * ((cell * 7) % 3) / 2.0f;
  const float value = 0.65f + 0.35f * ((cell * 5) % 4) / 3.0f;
  const float h = hue * 6.0f;
  const int sector = static_cast<int>(h) % 6;
  const float f = h - std::floor(h);
  const float p = value * (1 - saturation), q = value * (1 - saturation * f), t = value * (1 - saturation * (1 - f));
  switch (sector) {
    case 0: return {value, t, p};
    case 1: return {q, value, p};
    case 2: return {p, value, t};
    case 3: return {p, q, value};
    case 4: return {t, p, value};
    default: return {value, p, q};
  }
}

Vec3 portalCountColour(uint32_t crossings) {
  // 0 dark blue, then through cyan, green, yellow to red at 8 and more.
  static const Vec3 ramp[] = {{0.05f, 0.05f, 0.35f}, {0.0f, 0.35f, 0.9f}, {0.0f, 0.75f, 0.75f},
                              {0.1f, 0.8f, 0.2f},    {0.7f, 0.85f, 0.1f}, {0.95f, 0.65f, 0.05f},
                              {0.95f, 0.35f, 0.05f}, {0.85f, 0.1f, 0.1f}, {1.0f, 1.0f, 1.0f}};
  return ramp[std::min<uint32_t>(crossings, 8)];
}

void CellKernel::cross(RayState ray, const CellEvent& event, KernelOutputs& out) {
  // The neighbour traces the same ray from just before the portal (tMinBeforePortal).
  ray.tMin = tMinBeforePortal(toRay(ray), event.t);
  uint32_t next = event.neighborCell;
  if (ray.toSky && outdoors_) {
    if (ray.tMax < kInfinity) {
      // Out by another opening before the one it samples: that opening's
      // own samples count the sky seen this way.
      if (outdoors_->outdoors(next)) {
        ++out.counters.shadowBlocked;
        ++out.counters.raysFinished;
        return;
      }
    } else {
      const OutdoorPassage::End end = outdoors_->follow(toRay(ray), next);
      if (end.sky) {
        reachSky(ray, out);
        return;
      }
      next = end.cell;
      ray.tMin = end.tMin;
    }
  }
  out.crossings[next].push_back(ray);
}

void CellKernel::emitDaylightPhoton(size_t emitter, uint64_t photonsOfEmitter, uint64_t path, KernelOutputs& out) {
  const RayState photon = daylight_->emitPhoton(emitter, photonsOfEmitter, parameters_.seed, path);
  ++out.counters.photonsEmitted;
  // The photon came from the sky along its line: it exists only if that
  // line is clear outdoors. A blocked one is absorbed there, so the room
  // gets the unblocked share of the opening's power, as it should (the
  // light the outdoor geometry itself reflects is not followed). Where the
  // line crosses only outdoor cells without geometry it is traced at once.
  RayState probe = photon;
  probe.toSky = true;
  probe.direction = -photon.direction;
  probe.pixel = tracer_.cell().id();
  const OutdoorPassage::End end = outdoors_->follow(toRay(probe), daylight_->outdoorCell(emitter));
  if (end.sky) {
    tracePhoton(photon, out);
    return;
  }
  probe.tMin = end.tMin;
  ++out.counters.photonCrossings;
  out.crossings[end.cell].push_back(probe);
}

void CellKernel::traceSkyProbe(const RayState& probe, KernelOutputs& out) {
  RayState ray = probe;
  // Panes outdoors pass it with their transmittance, as they do shadow rays.
  const CellEvent event = traceThroughGlass(ray, out);
  switch (event.kind) {
    case CellEvent::Kind::Surface: ++out.counters.photonsAbsorbed; return;   // outdoors, in the photon's way
    case CellEvent::Kind::Portal:
      ++out.counters.photonCrossings;
      cross(ray, event, out);
      return;
    case CellEvent::Kind::Leave: reachSky(ray, out); return;
  }
}

void CellKernel::reachSky(const RayState& ray, KernelOutputs& out) {
  if (ray.kind == RayKind::Shadow) {
    ++out.counters.shadowReached;
    ++out.counters.raysFinished;
    addToFilm(ray.pixel, ray.weight, out);
    return;
  }
  // The photon as its opening emitted it (bit for bit: the same photon as
  // where nothing outdoors needs a probe), in the cell it starts in.
  RayState photon;
  photon.kind = RayKind::Photon;
  photon.pathId = ray.pathId;
  photon.origin = ray.origin;
  photon.direction = -ray.direction;
  photon.weight = ray.weight;
  if (ray.pixel == tracer_.cell().id()) {
    tracePhoton(photon, out);
    return;
  }
  ++out.counters.photonCrossings;
  out.crossings[ray.pixel].push_back(photon);
}

void CellKernel::tracePhoton(RayState photon, KernelOutputs& out) {
  const MeshView& mesh = tracer_.cell().mesh();
  const uint64_t seed = parameters_.seed;
  int glassEvents = 0;
  for (;;) {
    ++out.counters.raySegments;
    const CellEvent event = tracer_.trace(toRay(photon));
    if (event.kind == CellEvent::Kind::Leave) {
      ++out.counters.photonsEscaped;
      return;
    }
    if (event.kind == CellEvent::Kind::Portal) {
      ++out.counters.photonCrossings;
      cross(photon, event, out);
      return;
    }
    const Material& material = materialAt(event.primitive);
    if (material.glass()) {
      // Panes store no photons: they reflect or pass them on.
      if (++glassEvents > kMaxGlassEvents) {
        ++out.counters.photonsAbsorbed;
        return;
      }
      passOrReflect(photon, event, material);
      continue;
    }
    const Vec3 albedo = surfaceAlbedo(scene_.directory(), tracer_.cell(), material, event.primitive,
                                      photon.origin + photon.direction * event.t);
    const PhotonScatter scatter = scatterPhoton(photon, {mesh, event.primitive, event.t, event.u, event.v, material, &albedo},
                                                seed, parameters_.maxPhotonBounces);
    if (scatter.deposited) deposit(scatter.deposit, out);
    if (!scatter.bounced) {
      ++out.counters.photonsAbsorbed;
      return;
    }
  }
}

void CellKernel::traceCameraRay(const RayState& ray, KernelOutputs& out) {
  // A camera ray looks past at most this many hidden surfaces in one cell.
  constexpr int kMaxHiddenSurfaces = 64;
  int hiddenSkipped = 0, glassEvents = 0;
  RayState current = ray;
  for (;;) {
    ++out.counters.raySegments;
    const CellEvent event = tracer_.trace(toRay(current));
    if (!openingsHere_.empty() && parameters_.aov == JobSettings::Aov::Radiance &&
        seeLuminaire(current, event.kind == CellEvent::Kind::Leave ? current.tMax : event.t, out))
      return;
    switch (event.kind) {
      case CellEvent::Kind::Leave:
        ++out.counters.raysEscaped;
        ++out.counters.raysFinished;
        // Out of the building: the sky shows, and the sun's disc (its
        // share: seenByThisRay).
        if (daylight_ && parameters_.aov == JobSettings::Aov::Radiance && emissionSeenByThisRay(current)) {
          const SkyModel& sky = daylight_->sky();
          Vec3 radiance = sky.radiance(current.direction);
          if (sky.hasSun() && insideSunDisc(current.direction, sky.sunDirection()))
            radiance += sky.sunIrradiance() * (1.0f / kSunDiscSolidAngle);
          addToFilm(current.pixel, current.weight * radiance, out);
        }
        return;
      case CellEvent::Kind::Portal:
        ++out.counters.rayCrossings;
        // Light emitted beyond the camera's cell is the shaded samples'
        // share (emissionSeenByThisRay): an emission ray ends here.
        if (isEmissionRay(current)) {
          ++out.counters.raysFinished;
          return;
        }
        // A camera ray never bounces: its depth counts the portals it crossed.
        ++current.depth;
        cross(current, event, out);
        return;
      case CellEvent::Kind::Surface:
        // Cut-away surfaces (ceilings, their lamps) are invisible to the
        // camera from behind, as a ceiling is seen from above: look past
        // them. From the front (from the room below) they show.
        if (scene_.materials()[tracer_.cell().material(event.primitive)].hiddenFromCamera &&
            dot(tracer_.cell().mesh().geometricNormal(event.primitive), current.direction) >= 0.0f &&
            ++hiddenSkipped < kMaxHiddenSurfaces) {
          // Hits count only beyond tMin (every accelerator keeps the
          // interval open), so this looks strictly past the hidden surface.
          current.tMin = event.t;
          continue;
        }
        if (const Material& material = materialAt(event.primitive);
            material.glass() && parameters_.aov == JobSettings::Aov::Radiance && ++glassEvents <= kMaxGlassEvents) {
          passOrReflect(current, event, material);
          continue;
        }
        ++out.counters.raysFinished;   // here it ends: what it adds is its hit's
        if (parameters_.aov == JobSettings::Aov::Radiance && emissionSeenByThisRay(current))
          addEmission(current, event, out);
        if (isEmissionRay(current)) return;
        if (parameters_.aov == JobSettings::Aov::Cells)
          addToFilm(current.pixel, current.weight * cellColour(tracer_.cell().id()), out);
        else if (parameters_.aov == JobSettings::Aov::Portals)
          addToFilm(current.pixel, current.weight * portalCountColour(current.depth), out);
        else
          shade(current, event, out);
        return;
    }
  }
}

void CellKernel::shade(const RayState& ray, const CellEvent& hit, KernelOutputs& out) {
  const MeshView& mesh = tracer_.cell().mesh();
  const Material& material = scene_.materials()[tracer_.cell().material(hit.primitive)];
  bool front;
  const Vec3 normal = hitNormalFacing(mesh, hit.primitive, ray.direction, front);
  const Vec3 point = interiorHitPoint(mesh, hit.primitive, hit.u, hit.v);
  // Emission is added where the ray met it (traceCameraRay), not here.
  const Vec3 albedo = surfaceAlbedo(scene_.directory(), tracer_.cell(), material, hit.primitive, point);
  if (!(maxComponent(albedo) > 0)) return;
  const Vec3 brdf = albedo * (1.0f / kPi);

  sampleLights(ray, point, normal, brdf, out);
  // The sun's numbers are the camera path's direction dimensions at bounce
  // 0, which a camera ray (aimed by its pixel sample) leaves unused.
  if (daylight_ && daylight_->sky().hasSun())
    sampleSun(ray, point, normal, brdf,
              randomUniform(parameters_.seed, RandomStream::Camera, ray.pathId, 0, dim::DirectionU),
              randomUniform(parameters_.seed, RandomStream::Camera, ray.pathId, 0, dim::DirectionV), out);

  if (parameters_.gather > 0) {
    // Final gathering: cosine-distributed rays whose landing points take a
    // photon-map estimate, in whatever cell they land. With pdf cos/pi the
    // Lambertian weight (albedo/pi) cos / pdf is just the albedo.
    const uint32_t count = parameters_.gather;
    const Vec3 weight = ray.weight * albedo / float(count);
    const Vec3 origin = insideCell(offsetAlongNormal(point, normal));
    // The pixel's spp x count gather directions form one stratified
    // pattern (pixel_pattern.h); this sample takes its own count of them.
    const uint32_t spp = parameters_.spp;
    const uint32_t sample = static_cast<uint32_t>(ray.pathId % spp);
    const PixelPattern directions(parameters_.seed, ray.pixel, PatternUse::GatherDirection, spp * count);
    for (uint32_t i = 0; i < count; ++i) {
      const PatternPoint direction = directions.point(sample * count + i);
      RayState gather;
      gather.kind = RayKind::Gather;
      gather.depth = static_cast<uint16_t>(ray.depth + 1);
      gather.pathId = ray.pathId;
      gather.pixel = ray.pixel;
      gather.origin = origin;
      gather.direction = sampleCosineHemisphere(normal, direction.u, direction.v);
      gather.weight = weight;
      ++out.counters.gatherRays;
      traceGatherRay(gather, out);
    }
  } else if (photons_ && photons_->size() > 0) {
    // Indirect light: the density of photons that arrived after at least one bounce.
    addToFilm(ray.pixel,
              ray.weight * photons_->radiance(point, normal, albedo, parameters_.photonK,
                                              parameters_.photonRadius),
              out);
  }
}

Vec3 CellKernel::insideCell(const Vec3& point) const {
  const Bounds3& box = tracer_.cell().bounds();
  const float margin = surfaceOffset(point);
  Vec3 inside = point;
  for (int axis = 0; axis < 3; ++axis) {
    if (inside[axis] < box.lo[axis]) inside[axis] = std::min(box.lo[axis] + margin, box.hi[axis]);
    if (inside[axis] > box.hi[axis]) inside[axis] = std::max(box.hi[axis] - margin, box.lo[axis]);
  }
  return inside;
}

void CellKernel::addEmission(const RayState& ray, const CellEvent& hit, KernelOutputs& out) {
  const Material& material = materialAt(hit.primitive);
  if (!material.emissive()) return;
  bool front;
  hitNormalFacing(tracer_.cell().mesh(), hit.primitive, ray.direction, front);
  // Emitters are one-sided: only their front shows their radiance.
  if (front) addToFilm(ray.pixel, ray.weight * material.emission, out);
}

bool CellKernel::seeLuminaire(const RayState& ray, float end, KernelOutputs& out) {
  const AreaLight* seen = nullptr;
  for (const uint32_t id : openingsHere_) {
    const AreaLight& light = scene_.lights()[id];
    if (const std::optional<float> t = light.openingHit(ray.origin, ray.direction, ray.tMin, end)) {
      end = *t;   // the nearest so far; a later one must be nearer still
      seen = &light;
    }
  }
  if (!seen) return false;
  ++out.counters.raysFinished;
  if (emissionSeenByThisRay(ray)) addToFilm(ray.pixel, ray.weight * seen->openingRadiance(ray.direction), out);
  return true;
}

CellEvent CellKernel::traceThroughGlass(RayState& ray, KernelOutputs& out) const {
  CellEvent event;
  for (int glassEvents = 0;; ++glassEvents) {
    ++out.counters.raySegments;
    event = tracer_.trace(toRay(ray));
    if (event.kind != CellEvent::Kind::Surface || glassEvents >= kMaxGlassEvents) return event;
    const Material& material = materialAt(event.primitive);
    if (!material.glass()) return event;
    if (ray.kind == RayKind::Shadow || ray.toSky) {
      // A shadow ray (or a photon's way back to the sky) keeps its line:
      // the pane lets through its transmittance.
      const Vec3 paneNormal = normalize(tracer_.cell().mesh().geometricNormal(event.primitive));
      ray.weight = ray.weight * thinGlass(material, dot(paneNormal, ray.direction)).transmittance;
      ray.tMin = event.t;
    } else {
      passOrReflect(ray, event, material);
    }
  }
}

void CellKernel::traceGatherRay(const RayState& gathered, KernelOutputs& out) {
  RayState ray = gathered;
  // Through glass panes (or off them) to the surface the ray lands on.
  const CellEvent event = traceThroughGlass(ray, out);
  switch (event.kind) {
    case CellEvent::Kind::Leave:
      ++out.counters.raysEscaped;
      ++out.counters.raysFinished;
      return;
    case CellEvent::Kind::Portal:
      ++out.counters.rayCrossings;
      cross(ray, event, out);
      return;
    case CellEvent::Kind::Surface: {
      ++out.counters.raysFinished;   // it lands: its estimate is read now or with the pending ones
      // Emission is not gathered: direct light is sampled with shadow rays.
      const Material& material = materialAt(event.primitive);
      if (!photons_ || photons_->size() == 0 || !(maxComponent(material.albedo) > 0)) return;
      bool front;
      const Vec3 normal = hitNormalFacing(tracer_.cell().mesh(), event.primitive, ray.direction, front);
      const Vec3 point = ray.origin + ray.direction * event.t;
      const Vec3 albedo = surfaceAlbedo(scene_.directory(), tracer_.cell(), material, event.primitive, point);
      const PendingGather gather{point,     normal,          ray.weight, albedo, ray.pathId,
                                 ray.pixel, gatherKey(ray), event.t,    isSecondaryGather(ray)};
      if (!irradiance_) {
        readGather(gather, out);
        if (shortGathers_.size() >= kMaxPendingGathers) finishGathers(out);
        return;
      }
      pendingGathers_.push_back(gather);
      if (pendingGathers_.size() >= kMaxPendingGathers) finishGathers(out);
      return;
    }
  }
}

void CellKernel::readGather(const PendingGather& gather, KernelOutputs& out) {
  Vec3 radiance, perAlbedo;
  float radius = 0;   // of the estimate's photon disc
  if (irradiance_ && irradiance_->lookup(gather.point, gather.normal, perAlbedo, &radius)) {
    radiance = gather.albedo * perAlbedo;
  } else {
    // Each gather lookup is one of many averaged per pixel, so it can use
    // fewer photons than an estimate seen directly (Jensen 2001, §9.3.2).
    const uint32_t k = std::max(8u, parameters_.photonK / 4);
    radiance = photons_->radiance(gather.point, gather.normal, gather.albedo, k, parameters_.photonRadius, nullptr,
                                  &radius);
  }
  if (!gather.secondary && gather.distance < kShortGatherRadii * radius) {
    shortGathers_.push_back(gather);
    return;
  }
  addToFilm(gather.pixel, gather.weight * radiance, out);
}

void CellKernel::finishGathers(KernelOutputs& out) {
  // A short hit's own gather ray waits as a pending lookup in turn (and
  // makes no short hit).
  while (!pendingGathers_.empty() || !shortGathers_.empty()) {
    readPendingGathers(out);
    traceShortGathers(out);
  }
}

void CellKernel::traceShortGathers(KernelOutputs& out) {
  // Taken out first: tracing them may read the pending lookups
  // (finishGathers), which add no short hit.
  std::vector<PendingGather> shortGathers;
  shortGathers.swap(shortGathers_);
  for (size_t n = 0; n < shortGathers.size(); ++n) {
    if (n % 1024 == 0) checkStop();
    traceShortGather(shortGathers[n], out);
  }
}

void CellKernel::traceShortGather(const PendingGather& hit, KernelOutputs& out) {
  ++out.counters.shortGathers;
  // Its numbers: keyed by the gather ray's state, the same wherever it was traced.
  const auto number = [&](uint32_t dimension) {
    return randomUniform(parameters_.seed, RandomStream::Camera, hit.pathId, hit.key, dimension);
  };
  RayState from;   // what the hit's shadow rays and gather ray carry
  from.kind = RayKind::Gather;
  from.depth = kSecondaryGatherDepth;
  from.pathId = hit.pathId;
  from.pixel = hit.pixel;
  from.weight = hit.weight;
  const Vec3 brdf = hit.albedo * (1.0f / kPi);
  sampleLight(from, hit.point, hit.normal, brdf, number(dim::LightChoice), {number(dim::LightU), number(dim::LightV)},
              1, out);
  if (daylight_ && daylight_->sky().hasSun())
    sampleSun(from, hit.point, hit.normal, brdf, number(dim::SunU), number(dim::SunV), out);
  // Indirect light: one cosine-distributed gather ray (weight: the albedo, as in shade()).
  RayState gather = from;
  gather.origin = insideCell(offsetAlongNormal(hit.point, hit.normal));
  gather.direction = sampleCosineHemisphere(hit.normal, number(dim::DirectionU), number(dim::DirectionV));
  gather.weight = hit.weight * hit.albedo;
  ++out.counters.gatherRays;
  traceGatherRay(gather, out);
}

void CellKernel::readPendingGathers(KernelOutputs& out) {
  if (pendingGathers_.empty()) return;
  // Counting sort by the block of a 16 x 16 x 16 grid over the cell's box.
  constexpr uint32_t kSide = 16;
  const Bounds3& box = tracer_.cell().bounds();
  const Vec3 scale = Vec3(float(kSide)) / max(box.diagonal(), Vec3(1e-6f));
  const auto blockOf = [&](const Vec3& point) {
    uint32_t block = 0;
    for (int axis = 0; axis < 3; ++axis) {
      const float at = (point[axis] - box.lo[axis]) * scale[axis];
      const uint32_t step = at > 0 ? std::min(static_cast<uint32_t>(at), kSide - 1) : 0;
      block = block * kSide + step;
    }
    return block;
  };
  std::vector<uint32_t> blocks(pendingGathers_.size());
  std::vector<uint32_t> starts(kSide * kSide * kSide + 1, 0);
  for (size_t i = 0; i < pendingGathers_.size(); ++i) {
    blocks[i] = blockOf(pendingGathers_[i].point);
    ++starts[blocks[i] + 1];
  }
  for (size_t b = 1; b < starts.size(); ++b) starts[b] += starts[b - 1];
  std::vector<uint32_t> order(pendingGathers_.size());
  for (size_t i = 0; i < pendingGathers_.size(); ++i) order[starts[blocks[i]]++] = static_cast<uint32_t>(i);
  for (size_t n = 0; n < order.size(); ++n) {
    if (n % 4096 == 0) checkStop();
    readGather(pendingGathers_[order[n]], out);
  }
  pendingGathers_.clear();
}

void CellKernel::deposit(const StoredPhoton& photon, KernelOutputs& out) {
  ++out.counters.photonDeposits;
  // A map cannot hold such a photon (and never did: tables dropped them).
  if (!isFinite(photon.position) || !isFinite(photon.power)) return;
  // Each table's records lie on its own cell's lattice (PhotonFrame).
  out.deposits[tracer_.cell().id()].push_back(toRecord(photon, ownFrame_));
  // Copies for neighbours across a nearby portal, so their estimates near
  // the doorway see this side too (no seam at the threshold).
  thread_local std::vector<uint32_t> neighbors;
  tracer_.neighborsNear(photon.position, parameters_.photonRadius, neighbors);
  for (uint32_t neighbor : neighbors) {
    const PhotonFrame neighborFrame(scene_.cells()[neighbor].bounds, parameters_.photonRadius, ownFrame_.powerUnit());
    out.deposits[neighbor].push_back(toRecord(photon, neighborFrame));
    ++out.counters.photonCopies;
  }
}

void CellKernel::addToFilm(uint32_t pixel, const Vec3& radiance, KernelOutputs& out) {
  if (!isFinite(radiance)) {
    ++out.counters.nonFiniteContributions;
    return;
  }
  if (!out.film.add(pixel, radiance)) ++out.counters.filmOutOfRange;
}

void CellKernel::traceShadowRay(const RayState& shadow, KernelOutputs& out) {
  RayState ray = shadow;
  for (;;) {
    // Glass panes let through their transmittance of the light.
    const CellEvent event = traceThroughGlass(ray, out);
    switch (event.kind) {
      case CellEvent::Kind::Surface:
        ++out.counters.shadowBlocked;
        ++out.counters.raysFinished;
        return;
      case CellEvent::Kind::Portal:
        ++out.counters.rayCrossings;
        cross(ray, event, out);
        return;
      case CellEvent::Kind::Leave: break;
    }
    if (!(ray.tMax < kInfinity)) {
      // Out of the building: the sky is what a ray towards it reaches.
      if (ray.toSky) {
        reachSky(ray, out);
      } else {
        ++out.counters.raysEscaped;
        ++out.counters.raysFinished;
      }
      return;
    }
    // Nothing in this cell before tMax: the light is reached only if the
    // segment ends inside this cell; otherwise it left the building.
    if (!tracer_.cell().bounds().contains(ray.origin + ray.direction * ray.tMax)) {
      ++out.counters.raysEscaped;
      ++out.counters.raysFinished;
      return;
    }
    if (!ray.toSky) {
      ++out.counters.shadowReached;
      ++out.counters.raysFinished;
      addToFilm(ray.pixel, ray.weight, out);
      return;
    }
    // At the opening it samples: on through it, until the ray leaves the
    // building or something outdoors is in its way.
    ray.tMin = ray.tMax;
    ray.tMax = kInfinity;
  }
}

void CellKernel::addShadowRay(const RayState& ray, const Vec3& origin, const Vec3& direction, float distance,
                              const Vec3& contribution, bool toSky, KernelOutputs& out) {
  RayState shadow;
  shadow.kind = RayKind::Shadow;
  shadow.depth = ray.depth;
  shadow.pathId = ray.pathId;
  shadow.pixel = ray.pixel;
  shadow.origin = origin;
  shadow.direction = direction;
  // Stop just short of the light so its own triangles do not block it.
  shadow.tMax = distance * (1.0f - 1e-4f);
  shadow.weight = contribution;
  shadow.toSky = toSky;
  ++out.counters.shadowRays;
  traceShadowRay(shadow, out);
}

void CellKernel::sampleLights(const RayState& ray, const Vec3& point, const Vec3& normal, const Vec3& brdf,
                              KernelOutputs& out) {
  // The pixel's spp x samples light choices and points on lights form
  // stratified patterns (pixel_pattern.h); this sample takes its own.
  const uint32_t samples = parameters_.lightSamples;
  const uint32_t spp = parameters_.spp;
  const uint32_t sample = static_cast<uint32_t>(ray.pathId % spp);
  const PixelPattern choices(parameters_.seed, ray.pixel, PatternUse::LightChoice, spp * samples);
  const PixelPattern points(parameters_.seed, ray.pixel, PatternUse::LightPoint, spp * samples);
  for (uint32_t i = 0; i < samples; ++i) {
    const uint32_t index = sample * samples + i;
    sampleLight(ray, point, normal, brdf, choices.value(index), points.point(index), samples, out);
  }
}

void CellKernel::sampleLight(const RayState& ray, const Vec3& point, const Vec3& normal, const Vec3& brdf,
                             float choiceNumber, const PatternPoint& onLight, uint32_t samples, KernelOutputs& out) {
  // Direct light: a shadow ray to a point on a light chosen by the light
  // sampler; a daylight opening is a light of the sky's radiance beyond it.
  const LightChoice choice = lightSampler_->choose(point, normal, choiceNumber);
  if (choice.probability <= 0) return;
  const AreaLight& light = lights_[choice.light];
  if (light.isPoint()) {
    samplePointLight(ray, point, normal, brdf, light, choice.probability * float(samples), out);
    return;
  }
  const Vec3 target = light.pointAt(onLight.u, onLight.v);
  const Vec3 origin = insideCell(offsetAlongNormal(point, normal));
  const Vec3 toLight = target - origin;
  const float distance2 = dot(toLight, toLight);
  const float distance = std::sqrt(distance2);
  const Vec3 direction = toLight / distance;
  const float cosSurface = dot(normal, direction);
  const float cosLight = -dot(light.normal(), direction);
  if (cosSurface <= 0 || cosLight <= 0) return;
  const bool sky = choice.light >= scene_.lights().size();
  const Vec3 radiance = sky ? daylight_->sky().radiance(direction) : light.radiance;
  // Area sampling: pdf = 1 / area, converted to solid angle by d^2 / cos.
  const float geometry = cosSurface * cosLight * light.area() / distance2;
  addShadowRay(ray, origin, direction, distance,
               ray.weight * brdf * radiance * (geometry / (choice.probability * float(samples))), sky, out);
}

void CellKernel::samplePointLight(const RayState& ray, const Vec3& point, const Vec3& normal, const Vec3& brdf,
                                  const AreaLight& light, float probability, KernelOutputs& out) {
  // Illuminance from a point: E = I(direction) cos / d^2, no area to sample.
  const Vec3 origin = insideCell(offsetAlongNormal(point, normal));
  const Vec3 toLight = light.corner - origin;
  const float distance2 = dot(toLight, toLight);
  if (!(distance2 > 0)) return;
  const float distance = std::sqrt(distance2);
  const Vec3 direction = toLight / distance;
  const float cosSurface = dot(normal, direction);
  if (cosSurface <= 0) return;
  const Vec3 intensity = light.intensityToward(-direction);
  if (!(maxComponent(intensity) > 0)) return;
  addShadowRay(ray, origin, direction, distance, ray.weight * brdf * intensity * (cosSurface / (distance2 * probability)),
               false, out);
}

void CellKernel::sampleSun(const RayState& ray, const Vec3& point, const Vec3& normal, const Vec3& brdf, float u,
                           float v, KernelOutputs& out) {
  // A direction over the sun's disc: it reaches the point only through the
  // opening the ray towards it leaves by, the nearest it passes through,
  // and on past what stands outdoors.
  const Vec3 direction = sampleSunDisc(daylight_->sky().sunDirection(), u, v);
  const float cosSurface = dot(normal, direction);
  if (cosSurface <= 0) return;
  const Vec3 origin = insideCell(offsetAlongNormal(point, normal));
  std::optional<float> nearest;
  for (uint32_t k : nearOpenings_) {
    const AreaLight& opening = daylight_->openings()[k];
    if (dot(opening.normal(), direction) >= 0) continue;   // the sun is behind it
    const std::optional<float> t = DaylightEmitters::distanceThrough(opening, origin, direction);
    if (t && (!nearest || *t < *nearest)) nearest = t;
  }
  if (!nearest) return;
  addShadowRay(ray, origin, direction, *nearest, ray.weight * brdf * daylight_->sky().sunIrradiance() * cosSurface,
               true, out);
}

bool CellKernel::passOrReflect(RayState& ray, const CellEvent& hit, const Material& glass) const {
  const Vec3 geometric = normalize(tracer_.cell().mesh().geometricNormal(hit.primitive));
  const float cosIncident = dot(geometric, ray.direction);
  const GlassResponse response = thinGlass(glass, cosIncident);
  const RandomStream stream = ray.kind == RayKind::Photon ? RandomStream::Photon : RandomStream::Camera;
  const float u = randomUniform(parameters_.seed, stream, ray.pathId, glassKey(ray), dim::GlassChoice);
  if (u < response.reflectance) {
    // Reflected with probability R': the weight R' / R' is unchanged.
    const Vec3 facing = cosIncident < 0 ? geometric : -geometric;
    ray.origin = offsetAlongNormal(ray.origin + ray.direction * hit.t, facing);
    ray.direction = normalize(reflect(ray.direction, facing));
    ray.tMin = 0;
    ray.tMax = kInfinity;
    return true;
  }
  // Passed with probability 1 - R': the weight keeps the tint.
  ray.weight = ray.weight * glass.transmittance;
  ray.tMin = hit.t;
  return false;
}

}  // namespace portico
