#include "common/transport/film.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace portico {
namespace {

TEST(Film, SumsAreIndependentOfOrder) {
  std::mt19937 random(3);
  std::uniform_real_distribution<float> value(0, 20);
  std::vector<std::pair<uint32_t, Vec3>> contributions;
  for (int i = 0; i < 20000; ++i)
    contributions.push_back({uint32_t(random() % 64), Vec3(value(random), value(random) * 1e-4f, value(random) * 1e3f)});
  FilmAccumulator forward, shuffled;
  for (const auto& [pixel, rgb] : contributions) forward.add(pixel, rgb);
  std::shuffle(contributions.begin(), contributions.end(), random);
  for (const auto& [pixel, rgb] : contributions) shuffled.add(pixel, rgb);
  for (const auto& [pixel, sum] : forward.sums()) {
    const FixedRgb& other = shuffled.sums().at(pixel);
    EXPECT_EQ(sum.r, other.r);
    EXPECT_EQ(sum.g, other.g);
    EXPECT_EQ(sum.b, other.b);
  }
}

TEST(Film, NonFiniteAndNegativeContributionsAddNothing) {
  EXPECT_EQ(toFixed(std::numeric_limits<float>::quiet_NaN()), 0);
  EXPECT_EQ(toFixed(std::numeric_limits<float>::infinity()), 0);
  EXPECT_EQ(toFixed(-1.0f), 0);
  EXPECT_NEAR(fromFixed(toFixed(0.25f)), 0.25f, 1e-7f);
}

// An int64 sum wraps past 2^63 into a negative pixel (a contribution of
// 1e14 alone gets there): a contribution or a sum beyond the film's range
// is refused instead, and nothing of it is added.
TEST(Film, ASumBeyondTheFilmsRangeIsRefusedNeverWrapped) {
  FilmAccumulator film;
  EXPECT_FALSE(film.add(0, Vec3(1e14f, 1, 1)));
  EXPECT_EQ(film.sums().at(0).r, 0);
  const float nearLimit = float(kFilmMaxValue * 0.6);
  EXPECT_TRUE(film.add(1, Vec3(nearLimit, 0, 0)));
  EXPECT_FALSE(film.add(1, Vec3(nearLimit, 0, 0)));
  EXPECT_GT(film.sums().at(1).r, 0);
  EXPECT_LE(film.sums().at(1).r, kFilmMaxSum);
  // Two sums in range add without overflow, and a negative one is refused.
  FixedRgb sum{kFilmMaxSum / 2, 0, 0};
  EXPECT_TRUE(sum.addWithinRange({kFilmMaxSum / 2, 0, 0}));
  EXPECT_FALSE(sum.addWithinRange({1, 0, 0}));
  EXPECT_FALSE(sum.addWithinRange({0, -5, 0}));
  EXPECT_EQ(sum.r, kFilmMaxSum);
}

}  // namespace
}  // namespace portico
