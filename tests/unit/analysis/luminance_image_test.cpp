// Luminance images against 179 x Rec. 709 Y of each pixel's radiance, and
// their false-colour pictures' colours at known pixels.
#include "common/analysis/luminance_image.h"

#include <gtest/gtest.h>

#include <cmath>

#include "coordinator/cli/false_color_image.h"

namespace portico {
namespace {

// A 4 x 2 image: pixel p has radiance (p, 2p, 0.5p) / 10, the last one pure blue.
LinearImage rampImage() {
  LinearImage image;
  image.width = 4;
  image.height = 2;
  for (int p = 0; p < 8; ++p) image.rgb.insert(image.rgb.end(), {p * 0.1f, p * 0.2f, p * 0.05f});
  image.rgb[21] = 0, image.rgb[22] = 0, image.rgb[23] = 3.0f;
  return image;
}

TEST(LuminanceImage, EachPixelIs179TimesItsRec709Y) {
  const LinearImage radiance = rampImage();
  const LinearImage luminance = luminanceImage(radiance);
  ASSERT_EQ(luminance.width, 4u);
  ASSERT_EQ(luminance.rgb.size(), radiance.rgb.size());
  for (int p = 0; p < 7; ++p) {
    // 179 x (0.2126 x 0.1p + 0.7152 x 0.2p + 0.0722 x 0.05p) = 179 x 0.16791p cd/m^2.
    const double expected = 179.0 * 0.16791 * p;
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(luminance.rgb[3 * p + c], expected, 1e-4 * (1 + expected)) << p;
  }
  EXPECT_NEAR(luminance.rgb[21], 179.0 * 0.0722 * 3.0, 1e-4);   // blue weighs little
  const std::vector<double> values = luminanceValues(luminance);
  ASSERT_EQ(values.size(), 8u);
  EXPECT_NEAR(values[6], 179.0 * 0.16791 * 6, 1e-3);
}

TEST(FalseColorImage, PixelsTakeTheScalesColoursAndTheLegendSitsBeside) {
  const LinearImage luminance = luminanceImage(rampImage());
  FalseColorScale scale{.maximum = 100, .steps = 4, .unit = "cd/m2"};
  const cli::Canvas canvas = cli::drawFalseColorImage(luminance, scale);
  ASSERT_GT(canvas.width(), 4);
  for (int p = 0; p < 8; ++p) {
    const uint8_t* pixel = &canvas.pixels()[(size_t(p / 4) * canvas.width() + p % 4) * 3];
    const Rgb8 expected = scale.colorOf(luminance.rgb[3 * p]);
    EXPECT_EQ((Rgb8{pixel[0], pixel[1], pixel[2]}), expected) << p;
  }
  // Pixel 6 (180.3 cd/m^2) is over the maximum: red; pixel 0 is dark violet.
  EXPECT_EQ(scale.colorOf(luminance.rgb[18]), (Rgb8{230, 0, 0}));
  EXPECT_EQ(scale.colorOf(luminance.rgb[0]), (Rgb8{40, 0, 90}));
  // An automatic maximum: the 95th percentile (of 8 values the 7th smallest, pixel 5's 150.3 cd/m^2) rounded up.
  FalseColorScale resolved;
  cli::drawFalseColorImage(luminance, FalseColorScale{.maximum = 0}, &resolved);
  EXPECT_EQ(resolved.maximum, 200);
  EXPECT_EQ(cli::falseColorImagePath("out/view.exr"), "out/view.falsecolor.png");
}

TEST(FalseColorScale, ALogarithmicScaleSpansItsDecadesBelowTheTop) {
  const FalseColorScale log{.maximum = 1000, .steps = 3, .unit = "cd/m2", .decades = 3};
  EXPECT_DOUBLE_EQ(log.positionOf(1000), 1.0);
  EXPECT_DOUBLE_EQ(log.positionOf(1), 0.0);
  EXPECT_NEAR(log.positionOf(std::sqrt(1000.0)), 0.5, 1e-12);   // half way in decades, not in cd/m^2
  EXPECT_DOUBLE_EQ(log.positionOf(0.01), 0.0);                  // below the bottom: its colour
  EXPECT_DOUBLE_EQ(log.positionOf(5000), 1.0);
  EXPECT_DOUBLE_EQ(log.positionOf(NAN), 0.0);
  const std::vector<double> legend = log.legendValues();
  ASSERT_EQ(legend.size(), 4u);
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(legend[k], std::pow(10.0, k), 1e-9 * legend[k]) << k;
  EXPECT_EQ(log.colorOf(1000), spectrumColor(1.0));
  EXPECT_EQ(log.colorOf(10), spectrumColor(1.0 / 3));
  // The linear scale as before: value / maximum.
  const FalseColorScale linear{.maximum = 200, .steps = 4};
  EXPECT_DOUBLE_EQ(linear.positionOf(50), 0.25);
  EXPECT_DOUBLE_EQ(linear.valueAt(0.75), 150);
  EXPECT_EQ(linear.legendValues(), (std::vector<double>{0, 50, 100, 150, 200}));
}

}  // namespace
}  // namespace portico
