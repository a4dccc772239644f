// The ceiling panels of the generated buildings (`scene generate`), in
// photometric terms. By default a panel has the palette's radiance
// (12, 11, 9.5) whatever its size: 179 x pi x Y = 6 244 lm per m^2 of panel,
// 2 248 lm for a 0.6 m square, in a colour of about 5 700 K. `--panel-lumens`
// gives every panel that flux instead, and `--panel-colour-temperature` its
// colour (docs/photometric-lights.md).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <tuple>
#include <utility>

#include "common/math.h"
#include "common/scene/store/scene_store.h"

namespace portico {

struct PanelLighting {
  std::optional<double> lumens;              // per panel; unset: 6 244 lm per m^2 of panel
  std::optional<double> colourTemperature;   // kelvin; unset: the palette's colour
  bool isDefault() const { return !lumens && !colourTemperature; }
};

// The one-line problem with the options ("" when none), naming the option.
std::string panelLightingProblem(const PanelLighting& lighting);

// The panels' radiance and material: a store's material carries what the
// camera sees of a lamp, so panels of another radiance need a material of
// their own; one is added per distinct radiance (a building's panels come
// in a few sizes).
class PanelMaterials {
 public:
  // defaultMaterial: the palette's light material, which default panels use.
  PanelMaterials(SceneStoreWriter& writer, const PanelLighting& lighting, uint32_t defaultMaterial)
      : writer_(writer), lighting_(lighting), defaultMaterial_(defaultMaterial) {}
  // Sets the panel's radiance from its area; returns its material.
  uint32_t light(AreaLight& panel);

 private:
  SceneStoreWriter& writer_;
  const PanelLighting lighting_;
  const uint32_t defaultMaterial_;
  std::map<std::tuple<float, float, float>, uint32_t> materials_;
};

}  // namespace portico
