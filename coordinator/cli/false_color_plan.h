// False-colour plans of a lighting analysis, one picture per floor: each
// upward-facing sensor colours the square of the plan it stands for (side:
// the grid's spacing) by its value on a FalseColorScale, over it the walls
// cut 1.5 m above the floor (as `portico scene plan` draws them), the
// outlines and names of the rooms holding sensors, and a legend. x to the
// right, z downwards (the view from above).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/analysis/false_color_scale.h"
#include "common/analysis/sensor.h"
#include "common/scene/store/scene_store.h"
#include "coordinator/cli/png_canvas.h"

namespace portico::cli {

struct FalseColorPlanOptions {
  FalseColorScale scale{.maximum = 0};   // maximum <= 0: automaticScaleMaximum of the values drawn
  double cellSize = 0;      // metres each sensor's square spans; <= 0: the median nearest-neighbour distance
  int panelSize = 1000;     // pixels along the plan's longer side
  std::string title;        // above the plan, after the floor's name ("work plane 0.80 m")
};

// Where world x-z lands on a picture.
struct PlanFrame {
  int left = 0, top = 0;    // pixel of (minX, minZ)
  double scale = 1;         // pixels per metre
  float minX = 0, minZ = 0;
  int px(double x) const;
  int py(double z) const;
};

struct FalseColorPlan {
  uint32_t floor = 0;
  Canvas canvas{1, 1};
  PlanFrame frame;
  FalseColorScale scale;    // as drawn (its maximum resolved)
};

// `values` holds one value per sensor (lux, or a daylight factor), in the
// sensors' order. Sensors facing down or sideways (|dy| < 0.9) and those
// outside every cell are not drawn. One plan per floor holding a drawn
// sensor, by floor; all share one scale, so floors compare.
std::vector<FalseColorPlan> drawFalseColorPlans(const SceneStore& store, const std::vector<Sensor>& sensors,
                                                const std::vector<double>& values,
                                                const FalseColorPlanOptions& options);

// RESULTS.csv -> RESULTS.floor<N>.png beside it.
std::string falseColorPlanPath(const std::string& resultsPath, uint32_t floor);

// Draws the plans and writes each beside `resultsPath`; returns the paths.
std::vector<std::string> writeFalseColorPlans(const std::string& resultsPath, const SceneStore& store,
                                              const std::vector<Sensor>& sensors, const std::vector<double>& values,
                                              const FalseColorPlanOptions& options);

}  // namespace portico::cli
