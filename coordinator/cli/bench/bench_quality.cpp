#include "coordinator/cli/bench/bench_quality.h"

#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "common/util/child_process.h"
#include "coordinator/cli/bench/bench_plot.h"
#include "coordinator/cli/bench/image_score.h"
#include "common/util/csv_field.h"
#include "coordinator/cli/bench/mitsuba_ladder.h"

namespace portico::cli {
namespace {

namespace fs = std::filesystem;

std::string readFile(const fs::path& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

std::vector<std::string> splitOn(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::stringstream stream(text);
  for (std::string part; std::getline(stream, part, separator);)
    if (part.find_first_not_of(' ') != std::string::npos) parts.push_back(part);
  return parts;
}

// Runs argv to its end; throws naming `what` and its log when it fails.
void runChild(const std::vector<std::string>& argv, const fs::path& log, const std::string& what) {
  ChildProcess child(argv, log.string());
  if (child.wait() != 0) throw std::runtime_error(fmt::format("{} failed:\n{}", what, readFile(log)));
}

struct Rung {
  std::string settings;
  double seconds = 0;
  ImageScore score;
};

constexpr const char* kCsvHeader = "settings,seconds,mean_err,worst_block,rel_rmse_blocks,rel_mse,flip\n";

std::string csvRow(const Rung& r) {
  const ImageScore& s = r.score;
  return fmt::format("{},{:.3f},{:.4f},{:.4f},{:.4f},{:.5g},{}\n", csvField(r.settings), r.seconds, s.meanError,
                     s.worstBlock, s.blockRmse, s.relativeMse, s.flip ? fmt::format("{:.4f}", *s.flip) : "");
}

}  // namespace

int runBenchQuality(const BenchQualityOptions& options) {
  const fs::path scene = fs::path(options.sceneDirectory) / "scene.json";
  const fs::path reference = fs::path(options.sceneDirectory) / "reference.exr";
  if (!fs::exists(scene)) throw std::invalid_argument(fmt::format("{}: no scene.json", options.sceneDirectory));
  if (!fs::exists(reference))
    throw std::invalid_argument(fmt::format("{}: no reference.exr beside scene.json", options.sceneDirectory));
  const std::vector<std::string> ladder = splitOn(options.settings, ';');
  if (ladder.empty()) throw std::invalid_argument("--settings: no setting to render");

  const fs::path work = fs::temp_directory_path() / fmt::format("portico-bench-quality-{}", getpid());
  fs::remove_all(work);
  fs::create_directories(work);
  const std::string portico = findProgram("portico"), compare = findProgram("portico-compare");
  runChild({portico, "scene", "import", scene.string(), (work / "store").string()}, work / "import.log",
           "importing " + scene.string());

  std::vector<Rung> rungs;
  std::cout << kCsvHeader;
  for (size_t i = 0; i < ladder.size(); ++i) {
    const fs::path image = work / fmt::format("rung-{}.exr", i);
    std::vector<std::string> argv{portico, "render", (work / "store").string(), "-o", image.string(),
                                  "--workers", std::to_string(options.workers)};
    for (const std::string& word : splitOn(ladder[i], ' ')) argv.push_back(word);
    Rung rung{ladder[i], 0.0, {}};
    const auto started = std::chrono::steady_clock::now();
    runChild(argv, work / fmt::format("render-{}.log", i), "portico render " + ladder[i]);
    rung.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    rung.score = scoreImage(compare, image, reference, work / fmt::format("compare-{}.log", i));
    std::cout << csvRow(rung) << std::flush;
    rungs.push_back(rung);
  }

  // Mitsuba in the same run, on as many threads as portico has workers.
  std::vector<Rung> mitsubaRungs;
  if (options.mitsuba) {
    const std::string python = options.mitsubaPython.empty() ? defaultMitsubaPython() : options.mitsubaPython;
    for (const MitsubaRender& render :
         renderWithMitsuba(options.sceneDirectory, options.mitsubaSpp, options.workers, python, work / "mitsuba")) {
      Rung rung{fmt::format("mitsuba path --spp {}", render.spp), render.seconds, {}};
      rung.score = scoreImage(compare, render.image, reference, work / fmt::format("compare-mitsuba-{}.log", render.spp));
      std::cout << csvRow(rung) << std::flush;
      mitsubaRungs.push_back(rung);
    }
  }

  if (!options.csv.empty()) {
    std::ofstream out(options.csv);
    out << kCsvHeader;
    for (const Rung& r : rungs) out << csvRow(r);
    for (const Rung& r : mitsubaRungs) out << csvRow(r);
    if (!out) throw std::runtime_error(fmt::format("{}: cannot write", options.csv));
  }
  if (!options.plot.empty()) {
    PlotPanel panel{fmt::format("{}: error against time", fs::path(options.sceneDirectory).filename().string()),
                    "seconds (portico render, start-up included)", "relative error", true, true, {}};
    PlotSeries rmse, worst;
    rmse.label = "block RMSE", rmse.color = {31, 119, 180};
    worst.label = "worst block", worst.color = {214, 39, 40}, worst.dashed = true;
    for (const Rung& r : rungs) {
      rmse.x.push_back(r.seconds), rmse.y.push_back(r.score.blockRmse);
      worst.x.push_back(r.seconds), worst.y.push_back(r.score.worstBlock);
    }
    panel.series = {rmse, worst};
    if (!mitsubaRungs.empty()) {
      PlotSeries mitsuba;
      mitsuba.label = "Mitsuba", mitsuba.color = {44, 160, 44};
      panel.xLabel = "seconds (portico: command, Mitsuba: render)";
      for (const Rung& r : mitsubaRungs) mitsuba.x.push_back(r.seconds), mitsuba.y.push_back(r.score.blockRmse);
      panel.series.push_back(mitsuba);
    }
    writePlotPng(options.plot, {panel});
  }
  fs::remove_all(work);
  return 0;
}

}  // namespace portico::cli
