#include "common/transport/order_free_sum.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "common/rng.h"

namespace portico {
namespace {

Vec3 total(const std::vector<Vec3>& terms) {
  float largest = 0;
  for (const Vec3& t : terms)
    for (int c = 0; c < 3; ++c) largest = std::max(largest, std::abs(t[c]));
  OrderFreeSum sum(largest, static_cast<uint32_t>(terms.size()));
  for (const Vec3& t : terms) sum.add(t);
  return sum.total();
}

TEST(OrderFreeSum, AnyOrderGivesTheSameBitsAndTheExactSumRounded) {
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    std::vector<Vec3> terms;
    double exact[3] = {0, 0, 0};
    for (uint32_t i = 0; i < 64; ++i) {
      // Magnitudes over six orders, like photon powers times cone weights
      // (few enough that the double sum below is exact).
      Vec3 t;
      for (int c = 0; c < 3; ++c) {
        t[c] = std::ldexp(randomUniform(seed, RandomStream::Light, i, c, 0), -int(i % 20));
        exact[c] += t[c];
      }
      terms.push_back(t);
    }
    const Vec3 forward = total(terms);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(forward[c], static_cast<float>(exact[c])) << seed;
    std::reverse(terms.begin(), terms.end());
    EXPECT_EQ(total(terms), forward);
    std::rotate(terms.begin(), terms.begin() + 17, terms.end());
    EXPECT_EQ(total(terms), forward);
  }
}

TEST(OrderFreeSum, ZeroNegativeAndInfiniteTerms) {
  EXPECT_EQ(total({}), Vec3(0.0f));
  EXPECT_EQ(total({Vec3(0.0f), Vec3(0.0f)}), Vec3(0.0f));
  EXPECT_EQ(total({Vec3(1.0f, -2.0f, 0.5f), Vec3(-1.0f, 2.0f, 0.25f)}), Vec3(0.0f, 0.0f, 0.75f));
  EXPECT_EQ(total({Vec3(1.0f), Vec3(kInfinity, 1.0f, 1.0f)}), Vec3(kInfinity, 2.0f, 2.0f));
}

}  // namespace
}  // namespace portico
