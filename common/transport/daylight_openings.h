// Where daylight enters a building: the portals between an indoor cell and
// an outdoor one (a cell named `outside` or `sky`, or whose name starts
// with `outside-`, `sky-` or `facade-`: the generated buildings' sky and
// facade cells). Each opening is a light facing into its indoor cell, as
// pbrt-v4's portal lights are: daylight photons start on openings (their
// share by each opening's power), and shading points sample the sky
// through the openings of cells a few portals away and find the sun
// through the one their ray towards it leaves by; beyond the opening,
// what lies outdoors shadows them (outdoor_passage.h).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "common/rng.h"
#include "common/scene/store/scene_store.h"
#include "common/transport/ray_state.h"
#include "common/transport/sky_model.h"

namespace portico {

bool isOutdoorCell(const std::string& name);

// An opening, or a triangle of a portal that is not a parallelogram: an
// AreaLight of its indoor cell whose normal() points indoors; with
// `outdoorCells`, the outdoor cell beyond each.
std::vector<AreaLight> daylightOpenings(const SceneStore& scene, std::vector<uint32_t>* outdoorCells = nullptr);

// The daylight's photon emitters: emitter k < openings is the sky through
// opening k, emitter openings + k the sun through it. Their photons follow
// the scene's lights (batch light ids scene.lights().size() + emitter).
class DaylightEmitters {
 public:
  DaylightEmitters(const SceneStore& scene, const DaylightSettings& settings);
  size_t count() const { return 2 * openings_.size(); }
  const std::vector<AreaLight>& openings() const { return openings_; }
  const SkyModel& sky() const { return sky_; }
  uint32_t cell(size_t emitter) const { return openings_[emitter % openings_.size()].cell; }
  uint32_t outdoorCell(size_t emitter) const { return outdoorCells_[emitter % openings_.size()]; }
  // Power per channel entering through the opening (zero for the sun
  // through an opening facing away from it).
  Vec3 power(size_t emitter) const;
  // Photon `path` of `photonsOfEmitter`: from a uniform point of the
  // opening, moved just inside; sky photons in a cosine-distributed
  // direction, carrying the sky's radiance from where they come, sun
  // photons along the sun's rays, from a uniform point of its disc.
  RayState emitPhoton(size_t emitter, uint64_t photonsOfEmitter, uint64_t seed, uint64_t path) const;
  // The distance along unit `direction` from `origin` to the opening, if
  // the ray passes through it.
  static std::optional<float> distanceThrough(const AreaLight& opening, const Vec3& origin, const Vec3& direction);

 private:
  std::vector<AreaLight> openings_;
  std::vector<uint32_t> outdoorCells_;
  SkyModel sky_;
};

}  // namespace portico
