#include "coordinator/pass_error.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

#include "common/image/block_rule.h"

namespace portico {

namespace {
double radianceOf(const FixedRgb& pixel) {
  return (double(pixel.r) + double(pixel.g) + double(pixel.b)) / kFilmScale;
}

struct FilmBlocks {
  std::vector<double> sums;   // whole blocks only, row by row, as compareImages reads them
  double total = 0;           // the whole film, partial blocks at the edges included
};

FilmBlocks blocksOf(const std::vector<FixedRgb>& film, uint32_t width, uint32_t height) {
  FilmBlocks blocks;
  const uint32_t across = width / kErrorBlockSize, down = height / kErrorBlockSize;
  blocks.sums.assign(size_t(across) * down, 0.0);
  for (uint32_t y = 0; y < height; ++y)
    for (uint32_t x = 0; x < width; ++x) {
      const double value = radianceOf(film[size_t(y) * width + x]);
      blocks.total += value;
      const uint32_t bx = x / kErrorBlockSize, by = y / kErrorBlockSize;
      if (bx < across && by < down) blocks.sums[size_t(by) * across + bx] += value;
    }
  return blocks;
}
}  // namespace

PassError addPassAndEstimate(const std::vector<FixedRgb>& film, uint32_t width, uint32_t height, uint32_t passes,
                             PassBlockStatistics& statistics) {
  if (passes == 0) throw std::invalid_argument("addPassAndEstimate: no pass");
  if (film.size() != size_t(width) * height)
    throw std::invalid_argument(fmt::format("addPassAndEstimate: a film of {} pixels for {}x{}", film.size(), width,
                                            height));
  const FilmBlocks now = blocksOf(film, width, height);
  if (passes == 1) {
    statistics.sums.assign(now.sums.size(), 0.0);
    statistics.deviations.assign(now.sums.size(), 0.0);
  } else if (statistics.sums.size() != now.sums.size() || statistics.deviations.size() != now.sums.size()) {
    throw std::invalid_argument(fmt::format("addPassAndEstimate: {} blocks kept for a film of {}", statistics.sums.size(),
                                            now.sums.size()));
  }
  const double n = passes;
  for (size_t b = 0; b < now.sums.size(); ++b) {
    // This pass's block sum: the film's less the passes' before it.
    const double before = statistics.sums[b];
    const double pass = now.sums[b] - before;
    if (passes > 1) {
      const double meanBefore = before / (n - 1), meanNow = now.sums[b] / n;
      statistics.deviations[b] += (pass - meanBefore) * (pass - meanNow);
    }
    statistics.sums[b] = now.sums[b];
  }
  PassError error;
  if (passes < 2) return error;
  const double pixelsPerBlock = double(kErrorBlockSize) * kErrorBlockSize;
  const double imageMean = now.total / (n * 3.0 * width * height);   // of the average image, per channel
  double squares = 0;
  for (size_t b = 0; b < now.sums.size(); ++b) {
    const double passMean = statistics.sums[b] / n;   // a pass's block sum, on average
    if (!(passMean / (3.0 * pixelsPerBlock) > kDimBlockFractionOfMean * imageMean)) continue;
    const double variance = std::max(0.0, statistics.deviations[b] / (n - 1));
    const double relative = std::sqrt(variance / n) / passMean;
    squares += relative * relative;
    ++error.blocksUsed;
  }
  if (error.blocksUsed > 0) error.estimate = std::sqrt(squares / error.blocksUsed);
  return error;
}

}  // namespace portico
