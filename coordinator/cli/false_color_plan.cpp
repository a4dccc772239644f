// False-colour plans: per floor, a frame round the floor's cells, the
// sensors' squares, the walls, the rooms' outlines and names, a legend.
#include "coordinator/cli/false_color_plan.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "common/analysis/result_paths.h"
#include "common/scene/store/floor_levels.h"
#include "coordinator/cli/false_color_legend.h"
#include "coordinator/cli/plan_walls.h"

namespace portico::cli {

namespace {

constexpr Color kWallColor{40, 40, 40}, kOutlineColor{0, 0, 0}, kNoSensorColor{235, 235, 235};
constexpr float kSliceHeight = 1.5f;      // metres above the floor, as `scene plan`
constexpr double kUpFacing = 0.9;         // sensors with dy at least this are on the plan
constexpr int kMargin = 16;               // pixels round the plan
constexpr int kHeaderHeight = kTextHeight + 2 * 8;
constexpr double kMaxPixels = 36e6;

Color toColor(const Rgb8& c) { return {c[0], c[1], c[2]}; }

// The median distance from each sensor to its nearest neighbour in plan,
// among the sensors of its own cell: a regular grid's spacing.
double medianSpacing(const std::vector<Sensor>& sensors, const std::vector<size_t>& drawn) {
  std::map<int64_t, std::vector<size_t>> byCell;
  for (size_t i : drawn) byCell[sensors[i].cell].push_back(i);
  std::vector<double> nearest;
  for (const auto& [cell, members] : byCell)
    for (size_t i : members) {
      double best = HUGE_VAL;
      for (size_t j : members)
        if (j != i) {
          const double d = std::hypot(sensors[i].position.x - sensors[j].position.x,
                                      sensors[i].position.z - sensors[j].position.z);
          if (d > 1e-6) best = std::min(best, d);
        }
      if (best < HUGE_VAL) nearest.push_back(best);
    }
  if (nearest.empty()) return 0.5;   // lone sensors: the default grid spacing
  std::nth_element(nearest.begin(), nearest.begin() + nearest.size() / 2, nearest.end());
  return nearest[nearest.size() / 2];
}

// One floor's picture.
class FloorPlanDrawer {
 public:
  FloorPlanDrawer(const SceneStore& store, const FloorLevels& floors, uint32_t floor, const FalseColorScale& scale,
                  double cellSize, const FalseColorPlanOptions& options)
      : store_(store), floors_(floors), floor_(floor), scale_(scale), cellSize_(cellSize), options_(options) {
    for (const CellInfo& cell : store.cells())
      if (cell.triangleCount > 0 && floors.cellFloor[cell.id] == floor) cells_.push_back(cell.id), extent_.extend(cell.bounds);
  }

  FalseColorPlan draw(const std::vector<Sensor>& sensors, const std::vector<size_t>& onFloor,
                      const std::vector<double>& values) {
    for (size_t i : onFloor) {   // sensors' squares may reach past cells without triangles
      const float half = float(cellSize_ / 2);
      extent_.extend(sensors[i].position - Vec3(half, 0, half));
      extent_.extend(sensors[i].position + Vec3(half, 0, half));
    }
    layout();
    FalseColorPlan plan;
    plan.floor = floor_;
    plan.frame = frame_;
    plan.scale = scale_;
    plan.canvas = Canvas(width_, height_);
    Canvas& canvas = plan.canvas;

    const float level = std::abs(floors_.levels[floor_]) < 0.005f ? 0.0f : floors_.levels[floor_];
    canvas.text(kMargin, 8,
                fmt::format("{} {}  y = {:.2f} m{}", levelWord(store_), floor_, level,
                            options_.title.empty() ? "" : "  " + options_.title),
                kBlack);

    // Rooms with sensors: a pale ground first, so unlit gaps between squares read as "no sensor".
    std::set<int64_t> rooms;
    for (size_t i : onFloor) rooms.insert(sensors[i].cell);
    for (int64_t id : rooms) {
      const Bounds3& b = store_.cells()[size_t(id)].bounds;
      canvas.fill(frame_.px(b.lo.x), frame_.py(b.lo.z), frame_.px(b.hi.x), frame_.py(b.hi.z), kNoSensorColor);
    }
    for (size_t i : onFloor) {
      const double x = sensors[i].position.x, z = sensors[i].position.z, half = cellSize_ / 2;
      canvas.fill(frame_.px(x - half), frame_.py(z - half), frame_.px(x + half) - 1, frame_.py(z + half) - 1,
                  toColor(scale_.colorOf(values[i])));
    }
    for (const PlanSegment& s : sliceCells(store_, cells_, floors_.levels[floor_] + kSliceHeight))
      canvas.line(frame_.px(s.x0), frame_.py(s.z0), frame_.px(s.x1), frame_.py(s.z1), kWallColor, 2, false);
    for (int64_t id : rooms) drawRoomOutline(canvas, store_.cells()[size_t(id)]);
    drawLegend(canvas, width_ - kLegendWidth + 16, frame_.top, scale_);
    return plan;
  }

 private:
  void layout() {
    const double extentX = std::max(1e-3f, extent_.hi.x - extent_.lo.x);
    const double extentZ = std::max(1e-3f, extent_.hi.z - extent_.lo.z);
    double size = options_.panelSize;
    while (size > 64 && (size * extentX / std::max(extentX, extentZ) + kLegendWidth) *
                                (size * extentZ / std::max(extentX, extentZ) + kHeaderHeight) >
                            kMaxPixels)
      size *= 0.9;
    frame_.scale = size / std::max(extentX, extentZ);
    frame_.left = kMargin;
    frame_.top = kHeaderHeight + kMargin;
    frame_.minX = extent_.lo.x;
    frame_.minZ = extent_.lo.z;
    width_ = std::max(int(std::ceil(extentX * frame_.scale)) + 2 * kMargin + kLegendWidth,
                      textWidth(fmt::format("floor 00  y = -000.00 m  {}", options_.title)) + 2 * kMargin);
    height_ = std::max(int(std::ceil(extentZ * frame_.scale)), legendHeight(scale_)) + frame_.top + kMargin;
  }

  void drawRoomOutline(Canvas& canvas, const CellInfo& cell) {
    const int x0 = frame_.px(cell.bounds.lo.x), x1 = frame_.px(cell.bounds.hi.x);
    const int y0 = frame_.py(cell.bounds.lo.z), y1 = frame_.py(cell.bounds.hi.z);
    canvas.line(x0, y0, x1, y0, kOutlineColor, 1, false);
    canvas.line(x1, y0, x1, y1, kOutlineColor, 1, false);
    canvas.line(x1, y1, x0, y1, kOutlineColor, 1, false);
    canvas.line(x0, y1, x0, y0, kOutlineColor, 1, false);
    // The name on a white label where it fits: big buildings have rooms too small for it.
    const int width = textWidth(cell.name);
    if (width + 8 < x1 - x0 && kTextHeight + 8 < y1 - y0) {
      canvas.fill(x0 + 2, y0 + 2, x0 + width + 5, y0 + kTextHeight + 5, kWhite);
      canvas.text(x0 + 4, y0 + 4, cell.name, kBlack);
    }
  }

  const SceneStore& store_;
  const FloorLevels& floors_;
  uint32_t floor_;
  FalseColorScale scale_;
  double cellSize_;
  const FalseColorPlanOptions& options_;
  std::vector<uint32_t> cells_;
  Bounds3 extent_;
  PlanFrame frame_;
  int width_ = 1, height_ = 1;
};

}  // namespace

int PlanFrame::px(double x) const { return left + int(std::lround((x - minX) * scale)); }
int PlanFrame::py(double z) const { return top + int(std::lround((z - minZ) * scale)); }

std::vector<FalseColorPlan> drawFalseColorPlans(const SceneStore& store, const std::vector<Sensor>& sensors,
                                                const std::vector<double>& values,
                                                const FalseColorPlanOptions& options) {
  if (values.size() != sensors.size())
    throw std::invalid_argument(fmt::format("false-colour plan: {} sensors but {} values", sensors.size(), values.size()));
  const FloorLevels floors = findFloorLevels(store.cells());
  std::map<uint32_t, std::vector<size_t>> byFloor;
  std::vector<size_t> drawn;
  std::vector<double> drawnValues;
  for (size_t i = 0; i < sensors.size(); ++i) {
    const Sensor& s = sensors[i];
    if (s.cell < 0 || size_t(s.cell) >= store.cells().size() || s.direction.y < kUpFacing * length(s.direction))
      continue;
    byFloor[floors.cellFloor[size_t(s.cell)]].push_back(i);
    drawn.push_back(i);
    drawnValues.push_back(values[i]);
  }
  FalseColorScale scale = options.scale;
  if (!(scale.maximum > 0)) scale.maximum = automaticScaleMaximum(std::move(drawnValues));
  const double cellSize = options.cellSize > 0 ? options.cellSize : medianSpacing(sensors, drawn);
  std::vector<FalseColorPlan> plans;
  for (const auto& [floor, onFloor] : byFloor)
    plans.push_back(FloorPlanDrawer(store, floors, floor, scale, cellSize, options).draw(sensors, onFloor, values));
  return plans;
}

std::string falseColorPlanPath(const std::string& resultsPath, uint32_t floor) {
  return besideResults(resultsPath, fmt::format(".floor{}.png", floor));
}

std::vector<std::string> writeFalseColorPlans(const std::string& resultsPath, const SceneStore& store,
                                              const std::vector<Sensor>& sensors, const std::vector<double>& values,
                                              const FalseColorPlanOptions& options) {
  std::vector<std::string> paths;
  for (const FalseColorPlan& plan : drawFalseColorPlans(store, sensors, values, options)) {
    paths.push_back(falseColorPlanPath(resultsPath, plan.floor));
    writePng(paths.back(), plan.canvas, "false-colour plan");
  }
  return paths;
}

}  // namespace portico::cli
