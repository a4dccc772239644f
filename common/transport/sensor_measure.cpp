// CellKernel::measureSensors: what a lighting-analysis sensor reads. A
// sensor is shaded as a camera hit is (CellKernel::shade), on a white
// Lambertian surface at its point facing its direction, with a BRDF of 1
// instead of 1/pi: its light is then the irradiance on its plane, E = pi L.
// Direct light comes by shadow rays to lamps and to the sky and sun through
// openings and glass (the light sampler's and sampleSun's), indirect light
// by final gathering on the photon maps; each adds to its own film column
// of the sample's group (common/analysis/sensor_film.h).
#include <cmath>

#include "common/analysis/sensor_film.h"
#include "common/rng.h"
#include "common/transport/cell_kernel.h"
#include "common/transport/sampling.h"
#include "common/transport/surface_point.h"

namespace portico {

void CellKernel::measureSensors(const std::vector<SensorTask>& sensors, KernelOutputs& out) {
  const uint32_t spp = parameters_.spp;
  const uint32_t groups = sensorGroups(spp);
  const uint32_t lightSamples = parameters_.lightSamples;
  const uint32_t gather = parameters_.gather;
  const uint64_t seed = parameters_.seed;
  const Vec3 irradianceBrdf(1.0f);
  const bool sun = daylight_ && daylight_->sky().hasSun();
  for (const SensorTask& sensor : sensors) {
    const Vec3& point = sensor.position;
    const Vec3& normal = sensor.direction;
    const Vec3 origin = insideCell(offsetAlongNormal(point, normal));
    for (uint32_t group = 0; group < groups; ++group) {
      // Each group is a stratified estimate of its own: its patterns cover
      // its samples' light points and gather directions.
      const uint32_t samples = samplesInGroup(spp, groups, group);
      const uint32_t patternId = sensor.index * kSensorGroups + group;
      const PixelPattern choices(seed, patternId, PatternUse::LightChoice, samples * lightSamples);
      const PixelPattern onLights(seed, patternId, PatternUse::LightPoint, samples * lightSamples);
      const PixelPattern directions(seed, patternId, PatternUse::GatherDirection, samples * gather);
      // The row's columns add up to the mean of the groups' estimates.
      const Vec3 weight(1.0f / float(groups * samples));
      for (uint32_t k = 0; k < samples; ++k) {
        checkStop();
        RayState direct;
        direct.kind = RayKind::Camera;
        direct.pathId = uint64_t(sensor.index) * spp + group + uint64_t(k) * groups;
        direct.pixel = directSlot(sensor.index, group);
        direct.origin = point;
        direct.direction = normal;
        direct.weight = weight;
        ++out.counters.cameraRays;
        ++out.counters.raysFinished;   // the sample is its sensor's hit: its light comes by the rays below
        for (uint32_t i = 0; i < lightSamples; ++i) {
          const uint32_t index = k * lightSamples + i;
          sampleLight(direct, point, normal, irradianceBrdf, choices.value(index), onLights.point(index), lightSamples,
                      out);
        }
        if (sun)
          sampleSun(direct, point, normal, irradianceBrdf,
                    randomUniform(seed, RandomStream::Camera, direct.pathId, 0, dim::DirectionU),
                    randomUniform(seed, RandomStream::Camera, direct.pathId, 0, dim::DirectionV), out);
        const uint32_t indirectPixel = indirectSlot(sensor.index, group);
        if (gather > 0) {
          // Cosine-distributed: each gather ray's radiance times pi / count
          // estimates the irradiance.
          for (uint32_t i = 0; i < gather; ++i) {
            const PatternPoint d = directions.point(k * gather + i);
            RayState ray;
            ray.kind = RayKind::Gather;
            ray.depth = 1;
            ray.pathId = direct.pathId;
            ray.pixel = indirectPixel;
            ray.origin = origin;
            ray.direction = sampleCosineHemisphere(normal, d.u, d.v);
            ray.weight = weight * (kPi / float(gather));
            ++out.counters.gatherRays;
            traceGatherRay(ray, out);
          }
        } else if (photons_ && photons_->size() > 0) {
          // The photons' irradiance at the point: pi times the radiance a
          // white surface there would reflect.
          addToFilm(indirectPixel,
                    weight * (kPi * photons_->radiance(point, normal, irradianceBrdf, parameters_.photonK,
                                                       parameters_.photonRadius)),
                    out);
        }
      }
    }
    ++out.counters.sensorsMeasured;
  }
}

}  // namespace portico
