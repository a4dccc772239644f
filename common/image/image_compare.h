// Compares a rendered image with a reference the way the reference scenes
// ask (docs/validation.md): the image mean, and the means of square
// blocks, where dim blocks are judged against the image mean; beside them
// the per-pixel relative MSE, which sees the grain that block means average
// away (docs/image-quality.md).
#pragma once

#include <string>
#include <vector>

#include "common/image/block_rule.h"
#include "common/image/linear_image.h"

namespace portico {

struct BlockComparison {
  int x = 0, y = 0, size = 0;
  double reference = 0, image = 0;   // block means (average of R, G, B)
  double relativeError = 0;
  bool checked = false;              // reference mean above the threshold
};

struct ImageComparison {
  double referenceMean = 0, imageMean = 0;   // average of R, G, B over the image
  double meanRelativeError = 0;              // |image - reference| / reference of the means
  std::vector<BlockComparison> blocks;
  int blocksChecked = 0;
  int blocksOverLimit = 0;
  double worstBlockError = 0;
  // Root mean square of the checked blocks' relative errors (the "block
  // RMSE" of `portico bench quality`, for portico's images and Mitsuba's).
  double blockRmse = 0;
  // Mean over pixels and channels of (x - ref)^2 / (ref^2 + kRelativeMseEpsilon).
  double relativeMse = 0;
};

// The usual small epsilon of relative MSE (as Rousselle et al. and the
// denoising literature use it): keeps black reference pixels from dividing
// by zero, and weighs errors in pixels darker than ~0.1 less.
constexpr double kRelativeMseEpsilon = 1e-2;

double relativeMse(const LinearImage& image, const LinearImage& reference);

// Blocks of blockSize x blockSize pixels; a block is checked when its
// reference mean exceeds `threshold` times the reference image mean, and is
// over the limit when its relative error exceeds blockLimit.
ImageComparison compareImages(const LinearImage& image, const LinearImage& reference,
                              int blockSize = kErrorBlockSize, double threshold = kDimBlockFractionOfMean,
                              double blockLimit = 0.10);

std::string describe(const ImageComparison& comparison);

}  // namespace portico
