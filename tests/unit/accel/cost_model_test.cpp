// The `--accel auto` cost model: fitting, candidates, choices, calibration
// files, and the worker's rebuild rule.
#include "common/accel/cost_model.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "common/accel/uniform_grid.h"
#include "worker/accelerator_choice.h"

namespace portico {
namespace {

namespace fs = std::filesystem;

TEST(CostModelFit, RecoversTheCoefficientsOfExactlyLinearData) {
  const std::vector<double> truth{0.5, 2e-3, 7e-5};
  std::vector<std::vector<double>> x;
  std::vector<double> y;
  for (double n : {100.0, 1000.0, 5000.0, 20000.0, 100000.0}) {
    for (double v : {10.0, 1000.0, 50000.0}) {
      x.push_back({1.0, n, v});
      y.push_back(truth[0] + truth[1] * n + truth[2] * v);
    }
  }
  const std::vector<double> fit = fitNonNegativeRelative(x, y);
  ASSERT_EQ(fit.size(), 3u);
  for (size_t i = 0; i < 3; ++i) EXPECT_NEAR(fit[i], truth[i], 1e-6 * truth[i] + 1e-12) << i;
}

TEST(CostModelFit, NeverReturnsANegativeCost) {
  // y falls with the second feature: an unconstrained fit would give it a
  // negative coefficient; the fit drops it instead.
  std::vector<std::vector<double>> x;
  std::vector<double> y;
  std::mt19937 random(3);
  for (int i = 1; i <= 20; ++i) {
    x.push_back({1.0, double(i), double(i * i)});
    y.push_back(100.0 - 2.0 * i + 0.5 * i * i + std::uniform_real_distribution<double>(-1, 1)(random));
  }
  for (double c : fitNonNegativeRelative(x, y)) EXPECT_GE(c, 0.0);
}

TEST(CostModelFit, RefusesMismatchedInput) {
  EXPECT_THROW(fitNonNegativeRelative({}, {}), std::invalid_argument);
  EXPECT_THROW(fitNonNegativeRelative({{1.0}}, {1.0, 2.0}), std::invalid_argument);
}

CellShape room(double triangles) { return cellShape(triangles, Bounds3(Vec3(0, 0, 0), Vec3(6, 3, 5))); }

TEST(CostModel, GridCandidatesStayWithinTheVoxelBudgetAndFollowTheShape) {
  const CostModel model = CostModel::builtIn();
  const auto small = model.candidates(room(100));
  const auto large = model.candidates(room(200000));
  auto grids = [](const std::vector<AcceleratorCandidate>& list) {
    return std::count_if(list.begin(), list.end(), [](const auto& c) { return c.family == "grid"; });
  };
  EXPECT_LT(grids(small), grids(large));   // a finer grid is a candidate only for more triangles
  for (const auto& c : large) {
    if (c.family != "grid") continue;
    const auto features = buildFeatures(c, room(200000));
    EXPECT_LE(features[2], 64 * 200000.0);  // voxels
  }
  // Every family is a candidate whatever the size.
  for (const char* family : {"hgrid", "kd:median", "kd:sah", "kd:bbox", "bvh"})
    EXPECT_TRUE(std::any_of(small.begin(), small.end(), [&](const auto& c) { return c.family == family; }));
}

TEST(CostModel, MoreRaysNeverBuyACheaperBuildOrASlowerTrace) {
  // The choice minimises build + rays x trace, each candidate's weighted by
  // choiceWeight: as rays grow, the chosen structure's weighted build time
  // can only grow and its weighted per-ray time only fall.
  const CostModel model = CostModel::builtIn();
  for (double triangles : {200.0, 5000.0, 60000.0, 400000.0}) {
    double lastBuild = 0, lastTrace = 1e300;
    for (double rays = 1; rays <= 1e9; rays *= 4) {
      CostPrediction p = model.choose(room(triangles), rays);
      p.buildMs *= CostModel::choiceWeight(p.candidate);
      p.traceNsPerRay *= CostModel::choiceWeight(p.candidate);
      EXPECT_GE(p.buildMs, lastBuild - 1e-12) << triangles << " triangles, " << rays << " rays";
      EXPECT_LE(p.traceNsPerRay, lastTrace + 1e-12) << triangles << " triangles, " << rays << " rays";
      lastBuild = p.buildMs;
      lastTrace = p.traceNsPerRay;
    }
  }
}

TEST(CostModel, PredictsWhatItsCoefficientsSay) {
  CostModel model = CostModel::builtIn();
  model.families["kd:sah"] = {{1.0, 0.0, 0.0}, {10.0, 2.0}};
  const CostPrediction p = model.predictSpec("kd:sah", room(1024));
  EXPECT_DOUBLE_EQ(p.buildMs, 1.0);
  EXPECT_DOUBLE_EQ(p.traceNsPerRay, 10.0 + 2.0 * 10.0);
  EXPECT_DOUBLE_EQ(p.totalMs(1e6), 1.0 + 30.0);
  EXPECT_LT(model.predictSpec("embree", room(1024)).traceNsPerRay, 0);   // not a candidate
}


TEST(CostModel, PlainGridIsACandidateAtItsOwnResolutionAndWinsCloseCalls) {
  CostModel model = CostModel::builtIn();
  const CellShape cell = room(7400);
  const auto list = model.candidates(cell);
  ASSERT_FALSE(list.empty());
  EXPECT_EQ(list.front().spec, "grid");
  // Its features are those of the resolution the grid picks itself.
  const auto automatic = automaticGridResolution(cell.extent, 7400, UniformGridOptions{}.density);
  EXPECT_DOUBLE_EQ(buildFeatures(list.front(), cell)[2], double(automatic[0]) * automatic[1] * automatic[2]);
  // Make every grid cost the same per ray and nothing to build, the other
  // families dearer: then the plain grid ties with every grid:res=R and wins.
  model.families["grid"] = {{0, 0, 0}, {100, 0, 0}};
  for (const char* family : {"hgrid", "kd:median", "kd:sah", "kd:bbox", "bvh"})
    model.families[family] = {{1, 0, 0}, {200, 0}};
  EXPECT_EQ(model.choose(cell, 1e6).candidate.spec, "grid");
  // kd:sah 5 % cheaper per ray: within the margin, the plain grid stays.
  model.families["kd:sah"] = {{0, 0, 0}, {95, 0}};
  EXPECT_EQ(model.choose(cell, 1e6).candidate.spec, "grid");
  // 20 % cheaper: kd:sah.
  model.families["kd:sah"] = {{0, 0, 0}, {80, 0}};
  EXPECT_EQ(model.choose(cell, 1e6).candidate.spec, "kd:sah");
}
class CalibrationFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("portico-cost-model-" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    const fs::path path = dir_ / name;
    std::ofstream(path) << text;
    return path.string();
  }
  fs::path dir_;
};

TEST_F(CalibrationFile, RoundTrips) {
  CostModel model = CostModel::builtIn();
  model.families["grid"].trace = {111, 22, 333};
  model.origin = "test";
  const std::string path = (dir_ / "sub" / "calibration.json").string();
  model.save(path);
  const CostModel loaded = CostModel::load(path);
  EXPECT_EQ(loaded.origin, "test");
  EXPECT_EQ(loaded.families.at("grid").trace, model.families.at("grid").trace);
  EXPECT_EQ(loaded.choose(room(30000), 1e6).candidate.spec, model.choose(room(30000), 1e6).candidate.spec);
  EXPECT_FALSE(fs::exists(path + ".tmp"));
}

TEST_F(CalibrationFile, BadFilesAreRefusedNamingTheFileAndTheProblem) {
  auto message = [](const std::string& path) {
    try {
      CostModel::load(path);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string missing = (dir_ / "missing.json").string();
  EXPECT_NE(message(missing).find(missing), std::string::npos);
  EXPECT_NE(message(missing).find("cannot be read"), std::string::npos);
  const std::string garbage = write("garbage.json", "{ not json");
  EXPECT_NE(message(garbage).find("not JSON"), std::string::npos);
  const std::string version = write("version.json", R"({"version": 99, "families": {}})");
  EXPECT_NE(message(version).find("version"), std::string::npos);
  // A family missing, a coefficient negative, a coefficient missing.
  CostModel model = CostModel::builtIn();
  model.save((dir_ / "good.json").string());
  std::ifstream in(dir_ / "good.json");
  const std::string good((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  {
    std::string noFamily = good;
    noFamily.replace(noFamily.find("\"kd:bbox\""), 9, "\"kd:other\"");
    EXPECT_NE(message(write("family.json", noFamily)).find("no coefficients for kd:bbox"), std::string::npos);
  }
  {
    // A calibration written before bvh existed: bvh takes the built-in coefficients.
    nlohmann::json old = nlohmann::json::parse(good);
    old["families"].erase("bvh");
    const CostModel loaded = CostModel::load(write("old.json", old.dump()));
    EXPECT_EQ(loaded.families.at("bvh").trace, CostModel::builtIn().families.at("bvh").trace);
    EXPECT_NE(loaded.origin.find("bvh: built-in"), std::string::npos);
  }
  model.families["hgrid"].build[1] = -1;
  EXPECT_THROW(model.save((dir_ / "negative.json").string()), std::runtime_error);
  model.families["hgrid"].build = {1.0};
  EXPECT_THROW(model.save((dir_ / "short.json").string()), std::runtime_error);
}

TEST(AcceleratorChooser, RebuildsOnlyWhenTheFutureRaysPayForTheNewBuild) {
  CostModel model = CostModel::builtIn();
  // A grid that builds for free and traces slowly, a kd-tree that builds in
  // 10 ms and traces 10x faster; everything else out of the running.
  for (auto& [family, c] : model.families) {
    std::fill(c.build.begin(), c.build.end(), 0.0);
    std::fill(c.trace.begin(), c.trace.end(), 0.0);
    c.build[0] = 1e6;
    c.trace[0] = 1e6;
  }
  model.families["grid"] = {{0.0, 0.0, 0.0}, {1000.0, 0.0, 0.0}};
  model.families["kd:sah"] = {{10.0, 0.0, 0.0}, {100.0, 0.0}};
  AcceleratorChooser chooser(model);
  const CellShape cell = room(5000);
  // Few rays: the grid (10 ms of build buys back 900 ns a ray only beyond ~11 K rays).
  EXPECT_EQ(chooser.firstChoice(cell, 1000).candidate.family, "grid");
  const std::string grid = chooser.firstChoice(cell, 1000).candidate.spec;
  EXPECT_FALSE(chooser.betterChoice(grid, cell, 1000));
  EXPECT_FALSE(chooser.betterChoice(grid, cell, 12000));   // a win of < 25 %: not worth the risk
  const auto better = chooser.betterChoice(grid, cell, 1e6);
  ASSERT_TRUE(better);
  EXPECT_EQ(better->candidate.spec, "kd:sah");
  EXPECT_FALSE(chooser.betterChoice("kd:sah", cell, 1e9));   // already the best
  EXPECT_FALSE(chooser.betterChoice("embree", cell, 1e9));   // not the model's to replace
}

TEST(AcceleratorChooser, LearnsRaysPerUnitOfWork) {
  AcceleratorChooser chooser(CostModel::builtIn());
  chooser.learn(false, 1000, 3000);
  EXPECT_DOUBLE_EQ(chooser.expectedRays(false, 100), 300.0);
  chooser.learn(false, 1000, 3000);
  EXPECT_DOUBLE_EQ(chooser.expectedRays(false, 100), 300.0);
  chooser.learn(true, 10, 500);   // the render phase learns apart
  EXPECT_DOUBLE_EQ(chooser.expectedRays(true, 2), 100.0);
  EXPECT_DOUBLE_EQ(chooser.expectedRays(false, 100), 300.0);
  chooser.learn(false, 0, 10);   // nothing to learn from
  EXPECT_DOUBLE_EQ(chooser.expectedRays(false, 100), 300.0);
}

}  // namespace
}  // namespace portico
