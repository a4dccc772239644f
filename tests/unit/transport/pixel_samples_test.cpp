#include "common/transport/pixel_samples.h"

#include <gtest/gtest.h>

#include <set>
#include <vector>

namespace portico {
namespace {

// Every sample in its own fine column and fine row (N-rooks) and, for
// spp = m x n, in its own cell of the m x n grid.
TEST(PixelSamples, AreNRooksAndStratifiedOnTheGridForEverySampleCount) {
  std::vector<PixelSample> samples;
  std::vector<uint32_t> scratch;
  for (uint32_t spp : {1u, 2u, 4u, 7u, 12u, 16u, 64u, 100u}) {
    uint32_t m = 1;
    for (uint32_t d = 1; d * d <= spp; ++d)
      if (spp % d == 0) m = d;
    const uint32_t n = spp / m;
    for (uint32_t pixel : {0u, 1u, 977u, 65535u}) {
      pixelSamples(7, pixel, spp, samples, scratch);
      ASSERT_EQ(samples.size(), spp);
      std::set<uint32_t> columns, rows, cells;
      for (const PixelSample& s : samples) {
        ASSERT_GE(s.x, 0.0f);
        ASSERT_LT(s.x, 1.0f);
        ASSERT_GE(s.y, 0.0f);
        ASSERT_LT(s.y, 1.0f);
        columns.insert(uint32_t(s.x * float(spp)));
        rows.insert(uint32_t(s.y * float(spp)));
        cells.insert(uint32_t(s.x * float(m)) * n + uint32_t(s.y * float(n)));
      }
      EXPECT_EQ(columns.size(), spp) << spp << " spp, pixel " << pixel;
      EXPECT_EQ(rows.size(), spp) << spp << " spp, pixel " << pixel;
      EXPECT_EQ(cells.size(), spp) << spp << " spp, pixel " << pixel;
    }
  }
}

TEST(PixelSamples, DependOnlyOnTheSeedThePixelAndTheCountAndDifferBetweenPixels) {
  std::vector<PixelSample> a, b, c;
  std::vector<uint32_t> scratch;
  pixelSamples(3, 42, 16, a, scratch);
  pixelSamples(3, 42, 16, b, scratch);
  pixelSamples(3, 43, 16, c, scratch);
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].x, b[i].x);
    EXPECT_EQ(a[i].y, b[i].y);
  }
  bool differ = false;
  for (size_t i = 0; i < a.size(); ++i) differ |= a[i].x != c[i].x || a[i].y != c[i].y;
  EXPECT_TRUE(differ);
}

}  // namespace
}  // namespace portico
