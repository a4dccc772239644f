// Floor plans: a shared x-z frame for all panels (so floors line up), then
// per panel the cells, the portals and the lights of its floor.
#include "coordinator/cli/scene_plan.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <stdexcept>

#include "common/rng.h"
#include "common/scene/store/floor_levels.h"
#include "common/scene/store/portal_geometry.h"
#include "coordinator/cli/commands.h"
#include "coordinator/cli/plan_walls.h"

namespace portico::cli {

namespace {

constexpr Color kDoorColor{200, 20, 20}, kWindowColor{30, 100, 220}, kOpeningColor{130, 40, 170};
constexpr Color kLightColor{255, 215, 0}, kLightOutline{110, 80, 0};
constexpr Color kWallColor{60, 60, 60}, kCameraColor{0, 150, 60};
constexpr float kSliceHeight = 1.5f;                 // metres above the floor: walls cut at eye height
constexpr float kLargestOpening = 0.1f;              // of the plan's area: larger horizontal portals are air
constexpr int kMargin = 16;                          // around the footprint, in pixels
constexpr int kLabelHeight = kTextHeight + 2 * 8;    // the floor's label above its plan
constexpr double kMaxPixels = 64e6;                  // a picture larger than this gets smaller panels

// Pale, well separated colours: neighbours rarely look alike.
Color cellColor(uint32_t id) {
  const uint64_t h = mix64(id + 0x51ed27ull);
  return {uint8_t(140 + (h & 0xff) % 100), uint8_t(140 + (h >> 8 & 0xff) % 100), uint8_t(140 + (h >> 16 & 0xff) % 100)};
}

Color darker(const Color& c) { return {uint8_t(c[0] * 0.5), uint8_t(c[1] * 0.5), uint8_t(c[2] * 0.5)}; }

float footprintArea(const Bounds3& box) { return (box.hi.x - box.lo.x) * (box.hi.z - box.lo.z); }

// Where a floor's panel lies and how world x-z maps into it.
struct Panel {
  int x = 0, y = 0;            // top-left corner on the canvas
  double scale = 1;            // pixels per metre
  float minX = 0, minZ = 0;    // world corner at the panel's plan origin
  int px(float x) const { return this->x + kMargin + int(std::lround((x - minX) * scale)); }
  int py(float z) const { return y + kLabelHeight + kMargin + int(std::lround((z - minZ) * scale)); }
};

class PlanDrawer {
 public:
  PlanDrawer(const SceneStore& store, int floor, int panelSize)
      : store_(store), floors_(findFloorLevels(store.cells())) {
    chooseFloors(floor);
    chooseCells();
    layout(panelSize);
  }

  Canvas draw() {
    Canvas canvas(width_, height_);
    for (size_t i = 0; i < drawnFloors_.size(); ++i) drawFloor(canvas, panels_[i], drawnFloors_[i]);
    return canvas;
  }

 private:
  void chooseFloors(int floor) {
    const auto count = static_cast<int>(floors_.levels.size());
    if (floor >= count)
      throw std::runtime_error(fmt::format("scene store {}: no {} {} (it has {} {}s, 0 to {})", store_.directory(),
                                           levelWord(store_), floor, count, levelWord(store_), count - 1));
    for (int f = 0; f < count; ++f)
      if (floor < 0 || f == floor) drawnFloors_.push_back(static_cast<uint32_t>(f));
  }

  // Leaves out empty cells covering half the building's footprint or more:
  // a sky or an outdoors would hide every room under it.
  void chooseCells() {
    drawn_ = cellsToDraw(store_);
    for (const CellInfo& cell : store_.cells())
      if (drawn_[cell.id]) frame_.extend(cell.bounds);
  }

  void layout(int panelSize) {
    const size_t count = drawnFloors_.size();
    columns_ = count <= 3 ? int(count) : int(std::ceil(std::sqrt(double(count))));
    const int rows = int((count + columns_ - 1) / columns_);
    const double extentX = std::max(1e-3f, frame_.hi.x - frame_.lo.x);
    const double extentZ = std::max(1e-3f, frame_.hi.z - frame_.lo.z);
    // Shrink the panels until the picture fits the pixel budget.
    double size = panelSize;
    const auto pictureWidth = [&](double s) {
      return columns_ * (s * extentX / std::max(extentX, extentZ) + 2 * kMargin);
    };
    const auto pictureHeight = [&](double s) {
      return rows * (s * extentZ / std::max(extentX, extentZ) + 2 * kMargin + kLabelHeight);
    };
    while (size > 64 && pictureWidth(size) * pictureHeight(size) > kMaxPixels) size *= 0.9;
    const double scale = size / std::max(extentX, extentZ);
    // Wide enough for the label too.
    const int panelWidth =
        std::max(int(std::ceil(extentX * scale)), textWidth("floor 00  y = -000.00 m")) + 2 * kMargin;
    const int panelHeight = int(std::ceil(extentZ * scale)) + 2 * kMargin + kLabelHeight;
    width_ = columns_ * panelWidth;
    height_ = rows * panelHeight;
    for (size_t i = 0; i < count; ++i) {
      Panel panel;
      panel.x = int(i % columns_) * panelWidth;
      panel.y = int(i / columns_) * panelHeight;
      panel.scale = scale;
      panel.minX = frame_.lo.x;
      panel.minZ = frame_.lo.z;
      panels_.push_back(panel);
    }
    panelWidth_ = panelWidth;
    panelHeight_ = panelHeight;
  }

  void drawFloor(Canvas& canvas, const Panel& panel, uint32_t floor) {
    // Separator lines between panels, and the label.
    const int right = panel.x + panelWidth_ - 1, bottom = panel.y + panelHeight_ - 1;
    canvas.line(right, panel.y, right, bottom, kLightGrey, 1, false);
    canvas.line(panel.x, bottom, right, bottom, kLightGrey, 1, false);
    const float level = std::abs(floors_.levels[floor]) < 0.005f ? 0.0f : floors_.levels[floor];   // no "-0.00"
    canvas.text(panel.x + kMargin, panel.y + 8, fmt::format("{} {}  y = {:.2f} m", levelWord(store_), floor, level), kBlack);

    std::vector<const CellInfo*> cells;
    for (const CellInfo& cell : store_.cells())
      if (drawn_[cell.id] && floors_.cellFloor[cell.id] == floor) cells.push_back(&cell);
    std::stable_sort(cells.begin(), cells.end(), [](const CellInfo* a, const CellInfo* b) {
      return footprintArea(a->bounds) > footprintArea(b->bounds);
    });
    for (const CellInfo* cell : cells) {
      const int x0 = panel.px(cell->bounds.lo.x), x1 = panel.px(cell->bounds.hi.x);
      const int y0 = panel.py(cell->bounds.lo.z), y1 = panel.py(cell->bounds.hi.z);
      const Color color = cellColor(cell->id);
      canvas.fill(x0, y0, x1, y1, color);
      const Color outline = darker(color);
      canvas.line(x0, y0, x1, y0, outline, 1, false);
      canvas.line(x1, y0, x1, y1, outline, 1, false);
      canvas.line(x1, y1, x0, y1, outline, 1, false);
      canvas.line(x0, y1, x0, y0, outline, 1, false);
      // The name where it fits: big buildings have rooms too small for it.
      if (textWidth(cell->name) + 8 < x1 - x0 && kTextHeight + 8 < y1 - y0)
        canvas.text(x0 + 4, y0 + 4, cell->name, outline);
    }

    // Walls: the floor's triangles cut at eye height (door and window
    // openings show as gaps), under the portals drawn next.
    std::vector<uint32_t> ids;
    for (const CellInfo* cell : cells) ids.push_back(cell->id);
    for (const PlanSegment& s : sliceCells(store_, ids, floors_.levels[floor] + kSliceHeight))
      canvas.line(panel.px(s.x0), panel.py(s.z0), panel.px(s.x1), panel.py(s.z1), kWallColor, 2, false);

    for (const Portal& portal : store_.portals()) {
      const bool onFloor = (drawn_[portal.cellA] && floors_.cellFloor[portal.cellA] == floor) ||
                           (drawn_[portal.cellB] && floors_.cellFloor[portal.cellB] == floor);
      if (!onFloor) continue;
      const bool toLeftOut = !drawn_[portal.cellA] || !drawn_[portal.cellB];
      const Vec3 normal = newellNormal(portal.polygon);
      if (std::abs(normal.y) > 0.7f * length(normal)) {
        // A stair or slab opening; not the open air between two cells of an
        // outdoors, which would hatch over the whole plan.
        if (!toLeftOut && 0.5f * length(normal) < kLargestOpening * footprintArea(frame_))
          drawOpening(canvas, panel, portal.polygon);
      } else {
        drawWall(canvas, panel, portal.polygon, toLeftOut ? kWindowColor : kDoorColor, wallThickness(panel, portal));
      }
    }

    for (const AreaLight& light : store_.lights()) {
      if (floors_.cellFloor[light.cell] != floor || !drawn_[light.cell]) continue;
      const Vec3 c = light.center();
      const int x = panel.px(c.x), y = panel.py(c.z);
      canvas.fill(x - 4, y - 4, x + 4, y + 4, kLightOutline);
      canvas.fill(x - 3, y - 3, x + 3, y + 3, kLightColor);
    }

    // The camera: a dot and a short line towards its target.
    const Camera& camera = store_.camera();
    if (camera.cell < floors_.cellFloor.size() && floors_.cellFloor[camera.cell] == floor) {
      const int x = panel.px(camera.origin.x), y = panel.py(camera.origin.z);
      const float dx = camera.target.x - camera.origin.x, dz = camera.target.z - camera.origin.z;
      const float reach = 24.0f / std::max(1e-6f, std::sqrt(dx * dx + dz * dz));   // 24 pixels
      canvas.line(x, y, x + dx * reach, y + dz * reach, kCameraColor, 2, false);
      canvas.fill(x - 4, y - 4, x + 4, y + 4, kCameraColor);
    }
  }

  // A vertical portal seen from above is a segment: its two x-z points farthest apart.
  static void drawWall(Canvas& canvas, const Panel& panel, const std::vector<Vec3>& polygon, const Color& color,
                       int thickness) {
    size_t a = 0, b = 0;
    float longest = -1;
    for (size_t i = 0; i < polygon.size(); ++i)
      for (size_t j = i + 1; j < polygon.size(); ++j) {
        const float dx = polygon[i].x - polygon[j].x, dz = polygon[i].z - polygon[j].z;
        if (dx * dx + dz * dz > longest) longest = dx * dx + dz * dz, a = i, b = j;
      }
    canvas.line(panel.px(polygon[a].x), panel.py(polygon[a].z), panel.px(polygon[b].x), panel.py(polygon[b].z), color,
                thickness, false);
  }

  // 4 pixels, thinner where the cells are small on screen (a fine voxel
  // grid would otherwise be painted over by its portals).
  int wallThickness(const Panel& panel, const Portal& portal) const {
    double smallest = 1e30;
    for (uint32_t id : {portal.cellA, portal.cellB}) {
      if (!drawn_[id]) continue;
      const Bounds3& box = store_.cells()[id].bounds;
      smallest = std::min(smallest, std::min(box.hi.x - box.lo.x, box.hi.z - box.lo.z) * panel.scale);
    }
    return std::clamp(int(smallest / 8), 1, 4);
  }

  // A horizontal opening: its x-z rectangle, outlined and hatched.
  static void drawOpening(Canvas& canvas, const Panel& panel, const std::vector<Vec3>& polygon) {
    Bounds3 box;
    for (const Vec3& p : polygon) box.extend(p);
    const int x0 = panel.px(box.lo.x), x1 = panel.px(box.hi.x), y0 = panel.py(box.lo.z), y1 = panel.py(box.hi.z);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x)
        if ((x + y) % 8 < 2) canvas.set(x, y, kOpeningColor);
    canvas.line(x0, y0, x1, y0, kOpeningColor, 2, false);
    canvas.line(x1, y0, x1, y1, kOpeningColor, 2, false);
    canvas.line(x1, y1, x0, y1, kOpeningColor, 2, false);
    canvas.line(x0, y1, x0, y0, kOpeningColor, 2, false);
  }

  const SceneStore& store_;
  FloorLevels floors_;
  std::vector<uint32_t> drawnFloors_;
  std::vector<bool> drawn_;    // per cell
  Bounds3 frame_;              // x-z extent of every drawn cell, shared by all panels
  std::vector<Panel> panels_;
  int columns_ = 1, width_ = 1, height_ = 1, panelWidth_ = 1, panelHeight_ = 1;
};

}  // namespace

std::vector<bool> cellsToDraw(const SceneStore& store) {
  Bounds3 building;
  for (const CellInfo& cell : store.cells())
    if (cell.triangleCount > 0) building.extend(cell.bounds);
  if (building.empty())
    for (const CellInfo& cell : store.cells()) building.extend(cell.bounds);
  const float buildingArea = footprintArea(building);
  std::vector<bool> drawn(store.cells().size());
  for (const CellInfo& cell : store.cells())
    drawn[cell.id] = cell.triangleCount > 0 || footprintArea(cell.bounds) < 0.5f * buildingArea;
  return drawn;
}

Canvas drawFloorPlans(const SceneStore& store, int floor, int panelSize) {
  return PlanDrawer(store, floor, panelSize).draw();
}

int runScenePlan(const std::string& directory, const ScenePlanOptions& options) {
  const SceneStore store = SceneStore::open(directory);
  const Canvas canvas = drawFloorPlans(store, options.floor, options.panelSize);
  writePng(options.output, canvas, "floor plan");
  std::cout << fmt::format("{}: {}x{} pixels, {}\n", options.output, canvas.width(), canvas.height(),
                           options.floor < 0 ? fmt::format("{} {}(s)", findFloorLevels(store.cells()).levels.size(),
                                                                           levelWord(store))
                                             : fmt::format("{} {}", levelWord(store), options.floor));
  return 0;
}

}  // namespace portico::cli
