// False-colour plans of a hand-made room: the colour at each sensor's
// square is the scale's colour of its value, the scale's maximum rounds the
// largest value up, one picture per floor, and the PNG is written.
#include "coordinator/cli/false_color_plan.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "common/analysis/work_plane_grid.h"
#include "tests/unit/analysis/analysis_test_scenes.h"
#include "tests/unit/scene/scene_test_support.h"

namespace portico {
namespace {

using testing_support::boxRoom;
using testing_support::TempDirectory;
using testing_support::TestCell;
using testing_support::writeTestStore;


cli::Color pixelAt(const cli::Canvas& canvas, int x, int y) {
  const uint8_t* p = &canvas.pixels()[(size_t(y) * canvas.width() + x) * 3];
  return {p[0], p[1], p[2]};
}

cli::Color colorOf(const FalseColorScale& scale, double value) {
  const Rgb8 c = scale.colorOf(value);
  return {c[0], c[1], c[2]};
}

TEST(FalseColorScale, SpectrumEndsAndRoundMaxima) {
  FalseColorScale scale;
  scale.maximum = 500;
  EXPECT_EQ(scale.colorOf(0), (Rgb8{40, 0, 90}));
  EXPECT_EQ(scale.colorOf(500), (Rgb8{230, 0, 0}));
  EXPECT_EQ(scale.colorOf(5000), (Rgb8{230, 0, 0}));
  EXPECT_EQ(scale.colorOf(250), (Rgb8{0, 200, 0}));   // the middle stop
  EXPECT_EQ(spectrumColor(1.0 / 12), (Rgb8{20, 0, 160}));   // halfway between the first two stops
  EXPECT_EQ(roundScaleMaximum(550), 1000);
  EXPECT_EQ(roundScaleMaximum(480), 500);
  EXPECT_EQ(roundScaleMaximum(210), 250);
  EXPECT_DOUBLE_EQ(roundScaleMaximum(0.013), 0.02);
  EXPECT_EQ(roundScaleMaximum(0), 1);
  // The 95th percentile: of 0 .. 100 and one outlier, 95 (rounded up to 100), not the outlier.
  std::vector<double> values;
  for (int v = 0; v <= 100; ++v) values.push_back(v);
  values.push_back(1e6);
  values.push_back(NAN);
  EXPECT_EQ(automaticScaleMaximum(values), 100);
  EXPECT_EQ(FalseColorScale::label(62.5), "62.5");
  EXPECT_EQ(FalseColorScale::label(1500), "1.5k");
  EXPECT_EQ(FalseColorScale::label(0.25), "0.25");
}

TEST(FalseColorPlan, EachSensorsSquareHasTheColourOfItsValue) {
  TempDirectory dir;
  writeTestStore(dir / "store", {boxRoom("office", 0.0f), boxRoom("upstairs", 3.0f)});
  const SceneStore store = SceneStore::open(dir / "store");
  const WorkPlaneGrid grid = placeWorkPlaneGrid(store, {});
  ASSERT_EQ(grid.sensors.size(), 2 * 77u);
  std::vector<double> lux;
  for (const Sensor& s : grid.sensors) lux.push_back(100.0 * s.position.x + (s.cell == 1 ? 1000.0 : 0.0));
  cli::FalseColorPlanOptions options;
  options.panelSize = 600;
  const std::vector<cli::FalseColorPlan> plans = cli::drawFalseColorPlans(store, grid.sensors, lux, options);
  ASSERT_EQ(plans.size(), 2u);   // one per floor
  EXPECT_EQ(plans[0].floor, 0u);
  EXPECT_EQ(plans[1].floor, 1u);
  // The 95th percentile of both floors' values (1500 lx, upstairs) rounded up: one scale for both.
  EXPECT_EQ(plans[0].scale.maximum, 2000);
  EXPECT_EQ(plans[1].scale.maximum, 2000);
  for (size_t i = 0; i < grid.sensors.size(); ++i) {
    const Sensor& s = grid.sensors[i];
    const cli::FalseColorPlan& plan = plans[size_t(s.cell)];
    // The square's centre and a pixel a quarter of the spacing off it.
    const int x = plan.frame.px(s.position.x), y = plan.frame.py(s.position.z);
    const int quarter = int(0.125 * plan.frame.scale);
    EXPECT_EQ(pixelAt(plan.canvas, x, y), colorOf(plan.scale, lux[i])) << i;
    EXPECT_EQ(pixelAt(plan.canvas, x + quarter, y - quarter), colorOf(plan.scale, lux[i])) << i;
  }
  // A set maximum is kept.
  options.scale.maximum = 500;
  EXPECT_EQ(cli::drawFalseColorPlans(store, grid.sensors, lux, options)[0].scale.maximum, 500);
  const std::vector<cli::FalseColorPlan> capped = cli::drawFalseColorPlans(store, grid.sensors, lux, options);
  const cli::FalseColorPlan& first = capped[0];
  EXPECT_EQ(pixelAt(first.canvas, first.frame.px(5.5), first.frame.py(2.0)), colorOf(first.scale, 500));
}

TEST(FalseColorPlan, WallsAreDrawnOverTheSquares) {
  TempDirectory dir;
  writeTestStore(dir / "store", {boxRoom("office", 0.0f)});
  const SceneStore store = SceneStore::open(dir / "store");
  const WorkPlaneGrid grid = placeWorkPlaneGrid(store, {});
  const std::vector<double> lux(grid.sensors.size(), 300.0);
  const auto plans = cli::drawFalseColorPlans(store, grid.sensors, lux, {});
  const cli::FalseColorPlan& plan = plans.at(0);
  // The wall x = 0 half-way along z: 2 pixels wide, the room's 1-pixel black outline over its inner one.
  EXPECT_EQ(pixelAt(plan.canvas, plan.frame.px(0.0) - 1, plan.frame.py(2.0)), (cli::Color{40, 40, 40}));
  EXPECT_EQ(pixelAt(plan.canvas, plan.frame.px(0.0), plan.frame.py(2.0)), (cli::Color{0, 0, 0}));
  // Between the wall and the first sensor's square (0.25 m from the wall): no sensor there.
  EXPECT_EQ(pixelAt(plan.canvas, plan.frame.px(0.12), plan.frame.py(2.0)), (cli::Color{235, 235, 235}));
}

TEST(FalseColorPlan, WrittenBesideTheResults) {
  TempDirectory dir;
  writeTestStore(dir / "store", {boxRoom("office", 0.0f)});
  const SceneStore store = SceneStore::open(dir / "store");
  const WorkPlaneGrid grid = placeWorkPlaneGrid(store, {});
  const std::vector<double> lux(grid.sensors.size(), 300.0);
  const auto paths = cli::writeFalseColorPlans(dir / "RESULTS.csv", store, grid.sensors, lux, {});
  ASSERT_EQ(paths, std::vector<std::string>{dir / "RESULTS.floor0.png"});
  EXPECT_GT(std::filesystem::file_size(paths[0]), 1000u);
}

}  // namespace
}  // namespace portico
