#include "common/transport/pixel_pattern.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

namespace portico {
namespace {

// Every point in its own fine column and fine row (N-rooks) and, for
// count = m x n, in its own cell of the m x n grid; the 1-D values one in
// each of `count` intervals.
TEST(PixelPattern, IsNRooksAndStratifiedOnTheGridForEveryCount) {
  for (uint32_t count : {1u, 2u, 7u, 16u, 32u, 64u, 100u, 1000u}) {
    uint32_t m = 1;
    for (uint32_t d = 1; d * d <= count; ++d)
      if (count % d == 0) m = d;
    const uint32_t n = count / m;
    for (uint32_t pixel : {0u, 977u, 65535u}) {
      for (PatternUse use : {PatternUse::LightPoint, PatternUse::GatherDirection}) {
        const PixelPattern pattern(5, pixel, use, count);
        std::set<uint32_t> columns, rows, cells, intervals;
        for (uint32_t i = 0; i < count; ++i) {
          const PatternPoint p = pattern.point(i);
          ASSERT_GE(p.u, 0.0f);
          ASSERT_LT(p.u, 1.0f);
          ASSERT_GE(p.v, 0.0f);
          ASSERT_LT(p.v, 1.0f);
          columns.insert(uint32_t(p.u * float(count)));
          rows.insert(uint32_t(p.v * float(count)));
          cells.insert(uint32_t(p.u * float(m)) * n + uint32_t(p.v * float(n)));
          const float value = pattern.value(i);
          ASSERT_GE(value, 0.0f);
          ASSERT_LT(value, 1.0f);
          intervals.insert(uint32_t(value * float(count)));
        }
        EXPECT_EQ(columns.size(), count) << count << " points, pixel " << pixel;
        EXPECT_EQ(rows.size(), count) << count << " points, pixel " << pixel;
        EXPECT_EQ(cells.size(), count) << count << " points, pixel " << pixel;
        EXPECT_EQ(intervals.size(), count) << count << " points, pixel " << pixel;
      }
    }
  }
}

TEST(PixelPattern, DependsOnlyOnTheSeedThePixelTheUseAndTheCount) {
  const PixelPattern a(3, 42, PatternUse::GatherDirection, 64), b(3, 42, PatternUse::GatherDirection, 64);
  const PixelPattern otherPixel(3, 43, PatternUse::GatherDirection, 64);
  const PixelPattern otherUse(3, 42, PatternUse::LightPoint, 64);
  const PixelPattern otherSeed(4, 42, PatternUse::GatherDirection, 64);
  bool pixelDiffers = false, useDiffers = false, seedDiffers = false;
  for (uint32_t i = 0; i < 64; ++i) {
    EXPECT_EQ(a.point(i).u, b.point(i).u);
    EXPECT_EQ(a.point(i).v, b.point(i).v);
    EXPECT_EQ(a.value(i), b.value(i));
    pixelDiffers |= a.point(i).u != otherPixel.point(i).u;
    useDiffers |= a.point(i).u != otherUse.point(i).u;
    seedDiffers |= a.point(i).u != otherSeed.point(i).u;
  }
  EXPECT_TRUE(pixelDiffers);
  EXPECT_TRUE(useDiffers);
  EXPECT_TRUE(seedDiffers);
}

// Unbiased only if each sample's point is uniform over the square, and
// independent of the pixel's other uses: over many pixels, sample 0's
// point has mean 1/2 and no correlation with another use's point of the
// same sample (a fixed pairing, sample i always in stratum i, would fail).
TEST(PixelPattern, EachSamplesPointIsUniformAndUncorrelatedWithTheOtherUses) {
  constexpr int kPixels = 20000;
  for (uint32_t index : {0u, 5u, 63u}) {
    double sumU = 0, sumV = 0, sumProduct = 0, sumOther = 0;
    for (uint32_t pixel = 0; pixel < kPixels; ++pixel) {
      const PatternPoint p = PixelPattern(9, pixel, PatternUse::GatherDirection, 64).point(index);
      const PatternPoint q = PixelPattern(9, pixel, PatternUse::LightPoint, 64).point(index);
      sumU += p.u;
      sumV += p.v;
      sumOther += q.u;
      sumProduct += double(p.u) * q.u;
    }
    // Standard error of a mean of uniforms: sqrt(1/12 / 20000) ~ 0.002.
    EXPECT_NEAR(sumU / kPixels, 0.5, 0.01) << index;
    EXPECT_NEAR(sumV / kPixels, 0.5, 0.01) << index;
    const double covariance = sumProduct / kPixels - (sumU / kPixels) * (sumOther / kPixels);
    EXPECT_NEAR(covariance / (1.0 / 12.0), 0.0, 0.03) << index;
  }
}

}  // namespace
}  // namespace portico
