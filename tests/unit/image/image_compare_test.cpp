// The per-pixel relative MSE beside the block metric (image_compare.h).
#include <gtest/gtest.h>

#include "common/image/image_compare.h"

namespace portico {
namespace {

LinearImage filled(uint32_t width, uint32_t height, float value) {
  LinearImage image;
  image.width = width, image.height = height;
  image.rgb.assign(size_t(width) * height * 3, value);
  return image;
}

TEST(RelativeMse, IsZeroForTheSameImageAndTheMeanOfSquaredRelativeErrorsOtherwise) {
  const LinearImage reference = filled(32, 32, 0.5f);
  EXPECT_EQ(relativeMse(reference, reference), 0.0);
  LinearImage image = reference;
  image.rgb[0] = 1.0f;   // one channel of one pixel off by 0.5
  const double expected = 0.25 / (0.25 + kRelativeMseEpsilon) / double(reference.rgb.size());
  EXPECT_DOUBLE_EQ(relativeMse(image, reference), expected);
  EXPECT_DOUBLE_EQ(compareImages(image, reference).relativeMse, expected);
}

TEST(RelativeMse, EpsilonKeepsBlackReferencePixelsFinite) {
  const LinearImage reference = filled(16, 16, 0.0f);
  const LinearImage image = filled(16, 16, 0.1f);
  EXPECT_NEAR(relativeMse(image, reference), 0.01 / kRelativeMseEpsilon, 1e-6);
}

TEST(RelativeMse, SeesGrainThatBlockMeansAverageAway) {
  // Alternate pixels +-20 %: every 16x16 block mean is exact, relMSE is not.
  const LinearImage reference = filled(32, 32, 1.0f);
  LinearImage image = reference;
  for (size_t p = 0; p < size_t(32) * 32; ++p)
    for (int c = 0; c < 3; ++c) image.rgb[3 * p + c] = ((p + p / 32) % 2) ? 1.2f : 0.8f;
  const ImageComparison comparison = compareImages(image, reference);
  EXPECT_NEAR(comparison.blockRmse, 0.0, 1e-6);
  EXPECT_NEAR(comparison.relativeMse, 0.04 / (1.0 + kRelativeMseEpsilon), 1e-6);
}

TEST(RelativeMse, RefusesImagesOfDifferentSizes) {
  EXPECT_THROW(relativeMse(filled(16, 16, 1.0f), filled(16, 8, 1.0f)), std::invalid_argument);
}

}  // namespace
}  // namespace portico
