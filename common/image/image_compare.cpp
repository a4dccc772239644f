#include "common/image/image_compare.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

namespace portico {

namespace {
double meanOf(const LinearImage& image, int x0, int y0, int w, int h) {
  double sum = 0;
  for (int y = y0; y < y0 + h; ++y)
    for (int x = x0; x < x0 + w; ++x)
      for (int c = 0; c < 3; ++c) sum += image.rgb[(size_t(y) * image.width + x) * 3 + c];
  return sum / (3.0 * w * h);
}
}  // namespace

double relativeMse(const LinearImage& image, const LinearImage& reference) {
  if (image.rgb.size() != reference.rgb.size() || reference.rgb.empty())
    throw std::invalid_argument("relative MSE of images of different sizes");
  double sum = 0;
  for (size_t i = 0; i < reference.rgb.size(); ++i) {
    const double difference = double(image.rgb[i]) - reference.rgb[i];
    sum += difference * difference / (double(reference.rgb[i]) * reference.rgb[i] + kRelativeMseEpsilon);
  }
  return sum / double(reference.rgb.size());
}

ImageComparison compareImages(const LinearImage& image, const LinearImage& reference, int blockSize, double threshold,
                              double blockLimit) {
  if (image.width != reference.width || image.height != reference.height)
    throw std::invalid_argument(fmt::format("image is {}x{} but the reference is {}x{}", image.width, image.height,
                                            reference.width, reference.height));
  ImageComparison result;
  const int width = int(image.width), height = int(image.height);
  result.referenceMean = meanOf(reference, 0, 0, width, height);
  result.imageMean = meanOf(image, 0, 0, width, height);
  result.meanRelativeError = std::abs(result.imageMean - result.referenceMean) / result.referenceMean;
  for (int y = 0; y + blockSize <= height; y += blockSize)
    for (int x = 0; x + blockSize <= width; x += blockSize) {
      BlockComparison block;
      block.x = x;
      block.y = y;
      block.size = blockSize;
      block.reference = meanOf(reference, x, y, blockSize, blockSize);
      block.image = meanOf(image, x, y, blockSize, blockSize);
      block.checked = block.reference > threshold * result.referenceMean;
      block.relativeError = block.reference > 0 ? std::abs(block.image - block.reference) / block.reference : 0;
      if (block.checked) {
        ++result.blocksChecked;
        result.blocksOverLimit += block.relativeError > blockLimit;
        result.worstBlockError = std::max(result.worstBlockError, block.relativeError);
        result.blockRmse += block.relativeError * block.relativeError;
      }
      result.blocks.push_back(block);
    }
  if (result.blocksChecked > 0) result.blockRmse = std::sqrt(result.blockRmse / result.blocksChecked);
  result.relativeMse = relativeMse(image, reference);
  return result;
}

std::string describe(const ImageComparison& c) {
  const BlockComparison* worst = nullptr;
  for (const auto& b : c.blocks)
    if (b.checked && (!worst || b.relativeError > worst->relativeError)) worst = &b;
  std::string text = fmt::format(
      "image mean {:.5f} vs reference {:.5f}: {:.2f} % off; {} blocks checked, {} over the limit, block RMSE {:.2f} %; "
      "relMSE {:.3g}",
      c.imageMean, c.referenceMean, 100 * c.meanRelativeError, c.blocksChecked, c.blocksOverLimit, 100 * c.blockRmse,
      c.relativeMse);
  if (worst)
    text += fmt::format("; worst block at ({}, {}): {:.5f} vs {:.5f} ({:.1f} %)", worst->x, worst->y, worst->image,
                        worst->reference, 100 * worst->relativeError);
  return text;
}

}  // namespace portico
