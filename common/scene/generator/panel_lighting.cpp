#include "common/scene/generator/panel_lighting.h"

#include <fmt/format.h>

#include <cmath>

#include "common/photometry/lamp_colour.h"
#include "common/scene/generator/material_palette.h"

namespace portico {

std::string panelLightingProblem(const PanelLighting& lighting) {
  if (lighting.lumens && !(std::isfinite(*lighting.lumens) && *lighting.lumens > 0))
    return fmt::format("--panel-lumens {} must be a number of lumens above 0", *lighting.lumens);
  if (lighting.colourTemperature &&
      !(*lighting.colourTemperature >= kMinColourTemperature && *lighting.colourTemperature <= kMaxColourTemperature))
    return fmt::format("--panel-colour-temperature {} K lies outside {}-{} K", *lighting.colourTemperature,
                       kMinColourTemperature, kMaxColourTemperature);
  return {};
}

uint32_t PanelMaterials::light(AreaLight& panel) {
  if (lighting_.isDefault()) {
    panel.radiance = palette::kLightRadiance;
    return defaultMaterial_;
  }
  const double area = panel.area();
  const double lumens = lighting_.lumens ? *lighting_.lumens : lumensOfPower(palette::kLightRadiance * float(kPi * area));
  const Vec3 colour =
      lighting_.colourTemperature ? colourOfTemperature(*lighting_.colourTemperature) : palette::kLightRadiance;
  panel.radiance = radianceOfLumens(lumens, colour, area);
  const auto key = std::make_tuple(panel.radiance.x, panel.radiance.y, panel.radiance.z);
  if (const auto found = materials_.find(key); found != materials_.end()) return found->second;
  // As the palette's light: black, hidden from the camera seen from above.
  const uint32_t material = writer_.addMaterial(fmt::format("light-{:.0f}lm-{:.2f}m2", lumens, area), Vec3(0.0f),
                                                panel.radiance, true);
  materials_.emplace(key, material);
  return material;
}

}  // namespace portico
