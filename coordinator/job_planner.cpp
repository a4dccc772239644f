#include "coordinator/job_planner.h"

#include <capnp/message.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "common/accel/accelerator.h"
#include "common/net/message.h"
#include "common/transport/photon_shares.h"
#include "common/transport/sampling.h"

namespace portico {

void validateSpec(wire::JobSpec::Builder spec, const SceneStore& scene) {
  if (scene.lights().empty()) throw std::invalid_argument(fmt::format("scene {} has no lights", scene.directory()));
  if (spec.getWidth() == 0 || spec.getHeight() == 0) {
    spec.setWidth(scene.camera().width);
    spec.setHeight(scene.camera().height);
  }
  if (uint64_t(spec.getWidth()) * spec.getHeight() > (uint64_t(1) << 28))
    throw std::invalid_argument(fmt::format("image {}x{} is too large", spec.getWidth(), spec.getHeight()));
  if (spec.getSpp() == 0 || spec.getSpp() > 1u << 16)
    throw std::invalid_argument(fmt::format("spp {} must be between 1 and 65536", spec.getSpp()));
  if (spec.getPhotons() == 0 && spec.getAov() == wire::Aov::RADIANCE)
    throw std::invalid_argument("photons must be at least 1");
  if (spec.getPhotonK() == 0) spec.setPhotonK(64);
  if (!(spec.getPhotonRadius() > 0) || !std::isfinite(spec.getPhotonRadius()))
    throw std::invalid_argument(fmt::format("photon radius {} must be a positive number", spec.getPhotonRadius()));
  // A bad --accel is refused here, naming the problem, rather than failing
  // every cell's lease in the workers.
  if (spec.getAccel().size()) validateAcceleratorSpec(parseAcceleratorSpec(spec.getAccel().cStr()));
  if (spec.getRenderAccel().size()) validateAcceleratorSpec(parseAcceleratorSpec(spec.getRenderAccel().cStr()));
  if (scene.camera().cell >= scene.cells().size())
    throw std::invalid_argument(fmt::format("scene {}: the camera's cell {} does not exist", scene.directory(),
                                            scene.camera().cell));
}

void queuePhotonEmission(JobStore& store, uint64_t job, wire::JobSpec::Reader spec, const SceneStore& scene) {
  // The cell and portal pictures need no light: the photon phase is empty.
  if (spec.getAov() != wire::Aov::RADIANCE) return;
  const auto& lights = scene.lights();
  const std::vector<uint64_t> share = photonSharesOfLights(lights, spec.getPhotons());

  uint64_t nextPath = 0;
  for (size_t i = 0; i < lights.size(); ++i) {
    for (uint64_t first = 0; first < share[i]; first += kPhotonsPerEmitBatch) {
      const uint32_t count = static_cast<uint32_t>(std::min<uint64_t>(kPhotonsPerEmitBatch, share[i] - first));
      capnp::MallocMessageBuilder message;
      auto emit = message.initRoot<wire::RayBatch>().initEmit();
      emit.setLight(static_cast<uint32_t>(i));
      emit.setFirstPath(nextPath + first);
      emit.setCount(count);
      emit.setPhotonsOfLight(share[i]);
      store.addBatch(job, lights[i].cell, 0, BatchKind::Emit, count, net::packToString(message));
    }
    nextPath += share[i];
  }
}

void queueCameraRays(JobStore& store, uint64_t job, wire::JobSpec::Reader spec, const SceneStore& scene) {
  const uint32_t pixels = spec.getWidth() * spec.getHeight();
  const uint32_t pixelsPerBatch = std::max<uint32_t>(1, kSamplesPerCameraBatch / spec.getSpp());
  for (uint32_t first = 0; first < pixels; first += pixelsPerBatch) {
    const uint32_t count = std::min(pixelsPerBatch, pixels - first);
    capnp::MallocMessageBuilder message;
    auto camera = message.initRoot<wire::RayBatch>().initCamera();
    camera.setFirstPixel(first);
    camera.setPixelCount(count);
    store.addBatch(job, scene.camera().cell, 1, BatchKind::Camera, int64_t(count) * spec.getSpp(),
                   net::packToString(message));
  }
}

}  // namespace portico
