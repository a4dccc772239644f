#include "coordinator/cli/bench/bench_quality.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <array>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "common/util/child_process.h"
#include "coordinator/cli/bench/bench_plot.h"
#include "coordinator/cli/bench/image_score.h"
#include "common/util/csv_field.h"
#include "coordinator/cli/bench/peer_ladder.h"

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
  ImageScore score{};
};

constexpr const char* kCsvHeader = "settings,seconds,mean_err,worst_block,rel_rmse_blocks,rel_mse,flip\n";

std::string csvRow(const Rung& r) {
  const ImageScore& s = r.score;
  return fmt::format("{},{:.3f},{:.4f},{:.4f},{:.4f},{:.5g},{}\n", csvField(r.settings), r.seconds, s.meanError,
                     s.worstBlock, s.blockRmse, s.relativeMse, s.flip ? fmt::format("{:.4f}", *s.flip) : "");
}

// What the ladder renders: a reference scene (scene.json, imported once) or
// a named camera of a generated building (view.json: the generator's
// arguments, the camera and the image size), with reference.exr beside it.
struct Subject {
  std::string name;
  fs::path reference;
  std::vector<std::string> renderArguments;   // the store and the camera, for every rung
  std::string camera;
  uint32_t width = 0, height = 0;
  bool sceneJson = false;
};

Subject prepare(const BenchQualityOptions& options, const std::string& portico, const fs::path& work) {
  const fs::path folder(options.sceneDirectory);
  Subject subject;
  subject.name = folder.filename().string();
  subject.reference = folder / "reference.exr";
  const fs::path store = work / "store";
  subject.renderArguments = {store.string()};
  if (!fs::exists(folder / "scene.json") && !fs::exists(folder / "view.json"))
    throw std::invalid_argument(fmt::format("{}: neither scene.json nor view.json", options.sceneDirectory));
  if (!fs::exists(subject.reference))
    throw std::invalid_argument(fmt::format("{}: no reference.exr", options.sceneDirectory));
  if (fs::exists(folder / "scene.json")) {
    subject.sceneJson = true;
    runChild({portico, "scene", "import", (folder / "scene.json").string(), store.string()}, work / "import.log",
             "importing " + (folder / "scene.json").string());
  } else {
    const fs::path viewJson = folder / "view.json";
    nlohmann::json view;
    try {
      view = nlohmann::json::parse(readFile(viewJson));
      subject.camera = view.at("camera").get<std::string>();
      subject.width = view.at("width").get<uint32_t>();
      subject.height = view.at("height").get<uint32_t>();
      std::vector<std::string> generate{portico, "scene", "generate"};
      for (const std::string& word : splitOn(view.at("generate").get<std::string>(), ' ')) generate.push_back(word);
      generate.push_back(store.string());
      runChild(generate, work / "generate.log", "generating the building of " + viewJson.string());
    } catch (const nlohmann::json::exception& e) {
      throw std::invalid_argument(fmt::format("{}: {}", viewJson.string(), e.what()));
    }
    subject.renderArguments.insert(subject.renderArguments.end(),
                                   {"--camera", subject.camera, "--width", std::to_string(subject.width), "--height",
                                    std::to_string(subject.height)});
  }
  return subject;
}

struct PeerSeries {
  std::string label;
  std::vector<Rung> rungs;
  std::array<uint8_t, 3> color;
};

void runLadders(const BenchQualityOptions& options, const std::vector<std::string>& ladder, const fs::path& work);

}  // namespace

int runBenchQuality(const BenchQualityOptions& options) {
  const std::vector<std::string> ladder = splitOn(options.settings, ';');
  if (ladder.empty()) throw std::invalid_argument("--settings: no setting to render");

  const fs::path work = fs::temp_directory_path() / fmt::format("portico-bench-quality-{}", getpid());
  fs::remove_all(work);
  fs::create_directories(work);
  try {
    runLadders(options, ladder, work);
  } catch (...) {
    fs::remove_all(work);
    throw;
  }
  fs::remove_all(work);
  return 0;
}

namespace {

void runLadders(const BenchQualityOptions& options, const std::vector<std::string>& ladder, const fs::path& work) {
  const std::string portico = findProgram("portico"), compare = findProgram("portico-compare");
  const Subject subject = prepare(options, portico, work);

  std::vector<Rung> rungs;
  std::cout << kCsvHeader;
  for (size_t i = 0; i < ladder.size(); ++i) {
    const fs::path image = work / fmt::format("rung-{}.exr", i);
    std::vector<std::string> argv{portico, "render"};
    argv.insert(argv.end(), subject.renderArguments.begin(), subject.renderArguments.end());
    argv.insert(argv.end(), {"-o", image.string(), "--workers", std::to_string(options.workers)});
    for (const std::string& word : splitOn(ladder[i], ' ')) argv.push_back(word);
    Rung rung{ladder[i]};
    const auto started = std::chrono::steady_clock::now();
    runChild(argv, work / fmt::format("render-{}.log", i), "portico render " + ladder[i]);
    rung.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    rung.score = scoreImage(compare, image, subject.reference, work / fmt::format("compare-{}.log", i));
    std::cout << csvRow(rung) << std::flush;
    rungs.push_back(rung);
  }

  // The peers in the same run, on as many threads as portico has workers.
  std::vector<PeerSeries> peers;
  auto scorePeer = [&](const std::string& label, const std::string& rungPrefix, std::array<uint8_t, 3> color,
                       const std::vector<PeerRender>& renders) {
    PeerSeries series{label, {}, color};
    for (const PeerRender& render : renders) {
      Rung rung{fmt::format("{} --spp {}", rungPrefix, render.spp), render.seconds};
      rung.score = scoreImage(compare, render.image, subject.reference,
                              work / fmt::format("compare-{}.log", render.image.stem().string()));
      std::cout << csvRow(rung) << std::flush;
      series.rungs.push_back(rung);
    }
    peers.push_back(series);
  };
  const fs::path view = work / "view";
  if ((options.mitsuba && !subject.sceneJson) || options.luxcore)
    writePeerView(portico, (work / "store").string(), subject.camera, subject.width, subject.height, view);
  if (options.mitsuba) {
    const std::string python = options.mitsubaPython.empty() ? defaultMitsubaPython() : options.mitsubaPython;
    scorePeer("Mitsuba", "mitsuba path", {44, 160, 44},
              subject.sceneJson
                  ? renderWithMitsuba(options.sceneDirectory, options.mitsubaSpp, options.workers, python,
                                      work / "mitsuba")
                  : renderViewWithMitsuba(view, options.mitsubaSpp, options.workers, python));
  }
  if (options.luxcore)
    scorePeer(options.luxcorePhotonGi ? "LuxCore PhotonGI" : "LuxCore path",
              options.luxcorePhotonGi ? fmt::format("luxcore path+photongi {}", options.luxcorePhotonGi)
                                      : "luxcore path",
              {148, 103, 189}, renderViewWithLuxcore(view, options.luxcoreSpp, options.workers, options.luxcorePhotonGi));

  if (!options.csv.empty()) {
    std::ofstream out(options.csv);
    out << kCsvHeader;
    for (const Rung& r : rungs) out << csvRow(r);
    for (const PeerSeries& peer : peers)
      for (const Rung& r : peer.rungs) out << csvRow(r);
    if (!out) throw std::runtime_error(fmt::format("{}: cannot write", options.csv));
  }
  if (!options.plot.empty()) {
    PlotPanel panel{fmt::format("{}: error against time", subject.name),
                    "seconds (portico render, start-up included)", "relative error", true, true, {}};
    PlotSeries rmse, worst;
    rmse.label = "block RMSE", rmse.color = {31, 119, 180};
    worst.label = "worst block", worst.color = {214, 39, 40}, worst.dashed = true;
    for (const Rung& r : rungs) {
      rmse.x.push_back(r.seconds), rmse.y.push_back(r.score.blockRmse);
      worst.x.push_back(r.seconds), worst.y.push_back(r.score.worstBlock);
    }
    panel.series = {rmse, worst};
    for (const PeerSeries& peer : peers) {
      PlotSeries series;
      series.label = peer.label + " block RMSE", series.color = peer.color;
      panel.xLabel = "seconds (portico: command, peers: render)";
      for (const Rung& r : peer.rungs) series.x.push_back(r.seconds), series.y.push_back(r.score.blockRmse);
      panel.series.push_back(series);
    }
    writePlotPng(options.plot, {panel});
  }
}

}  // namespace

}  // namespace portico::cli
