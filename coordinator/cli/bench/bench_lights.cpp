#include "coordinator/cli/bench/bench_lights.h"

#include <fmt/format.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <vector>

#include "common/util/child_process.h"
#include "coordinator/cli/bench/accel_measure.h"
#include "coordinator/cli/bench/image_score.h"
#include "coordinator/cli/bench/pipeline_run.h"

namespace portico::cli {
namespace {

namespace fs = std::filesystem;

struct LightsRun {
  std::string sampler;
  uint32_t spp = 0, run = 0;
  PipelineRunStats stats;
  ImageScore score;
};

constexpr const char* kCsvHeader =
    "sampler,spp,run,render_s,photons_s,wall_s,shadow_rays,block_rmse,mean_err,worst_block,rel_mse\n";

std::string csvRow(const LightsRun& r) {
  return fmt::format("{},{},{},{:.3f},{:.3f},{:.3f},{},{:.5f},{:.5f},{:.5f},{:.5g}\n", r.sampler, r.spp, r.run,
                     r.stats.renderSeconds, r.stats.photonSeconds, r.stats.wallSeconds, r.stats.shadowRays,
                     r.score.blockRmse, r.score.meanError, r.score.worstBlock, r.score.relativeMse);
}

PipelineRunSpec viewSpec(const BenchLightsOptions& o, const std::string& sampler, uint32_t spp) {
  PipelineRunSpec spec;
  spec.store = fs::absolute(o.store).string();
  spec.workers = o.workers;
  spec.photons = o.photons;
  spec.seed = o.seed;
  spec.spp = spp, spec.gather = o.gather, spec.width = o.width, spec.height = o.height;
  spec.accel = o.accel;
  spec.memory = o.memory;
  spec.moreArguments = {"--camera", o.camera, "--light-sampler", sampler};
  return spec;
}

std::vector<double> column(const std::vector<LightsRun>& runs, const std::string& sampler, double (*field)(const LightsRun&)) {
  std::vector<double> values;
  for (const LightsRun& r : runs)
    if (r.sampler == sampler) values.push_back(field(r));
  return values;
}

}  // namespace

int runBenchLights(const BenchLightsOptions& o) {
  if (o.runs == 0) throw std::invalid_argument("--runs: at least 1");
  const fs::path work = fs::temp_directory_path() / fmt::format("portico-bench-lights-{}", getpid());
  fs::remove_all(work);
  fs::create_directories(work);
  const std::string compare = findProgram("portico-compare");

  fs::path reference = o.reference;
  if (reference.empty()) {
    reference = o.keepReference.empty() ? work / "reference.exr" : fs::path(o.keepReference);
    PipelineRunSpec spec = viewSpec(o, o.referenceSampler, o.referenceSpp);
    spec.keepImage = reference;
    std::cerr << fmt::format("rendering the reference: {} spp, --light-sampler {} ...\n", o.referenceSpp,
                             o.referenceSampler);
    const PipelineRunStats stats = runPipeline(spec, work, "reference-run");
    std::cerr << fmt::format("reference: render phase {:.1f} s\n", stats.renderSeconds);
  } else if (!fs::exists(reference)) {
    throw std::invalid_argument(fmt::format("{}: no such reference image", reference.string()));
  }

  // Interleaved, and the order swapped every round: a machine that slows
  // down or speeds up during the bench weighs on both samplers alike.
  std::vector<LightsRun> runs;
  std::cout << kCsvHeader;
  for (uint32_t round = 0; round < o.runs; ++round) {
    const std::vector<std::string> order =
        round % 2 == 0 ? std::vector<std::string>{"scan", "tree"} : std::vector<std::string>{"tree", "scan"};
    for (const std::string& sampler : order) {
      PipelineRunSpec spec = viewSpec(o, sampler, sampler == "tree" && o.treeSpp ? o.treeSpp : o.spp);
      const fs::path image = work / fmt::format("{}-{}.exr", sampler, round);
      spec.keepImage = image;
      LightsRun run{sampler, spec.spp, round, runPipeline(spec, work, fmt::format("run-{}-{}", sampler, round)), {}};
      run.score = scoreImage(compare, image, reference, work / fmt::format("compare-{}-{}.log", sampler, round));
      std::cout << csvRow(run) << std::flush;
      runs.push_back(run);
    }
  }

  const auto renderSeconds = [](const LightsRun& r) { return r.stats.renderSeconds; };
  const auto blockRmse = [](const LightsRun& r) { return r.score.blockRmse; };
  const auto worstBlock = [](const LightsRun& r) { return r.score.worstBlock; };
  std::cout << fmt::format(
      "\n| sampler | spp | render phase (median of {}) | block RMSE | worst block |\n|---|---|---|---|---|\n", o.runs);
  for (const char* sampler : {"scan", "tree"})
    std::cout << fmt::format("| {} | {} | {:.2f} s | {:.2f} % | {:.2f} % |\n", sampler,
                             sampler == std::string("tree") && o.treeSpp ? o.treeSpp : o.spp,
                             median(column(runs, sampler, renderSeconds)), 100 * median(column(runs, sampler, blockRmse)),
                             100 * median(column(runs, sampler, worstBlock)));
  const double scan = median(column(runs, "scan", renderSeconds)), tree = median(column(runs, "tree", renderSeconds));
  std::cout << fmt::format("tree / scan: render phase {:.2f}x as fast; load average {}\n", scan / tree, loadAverage());

  if (!o.csv.empty()) {
    std::ofstream out(o.csv);
    out << kCsvHeader;
    for (const LightsRun& r : runs) out << csvRow(r);
    if (!out) throw std::runtime_error(fmt::format("{}: cannot write", o.csv));
  }
  fs::remove_all(work);
  return 0;
}

}  // namespace portico::cli
