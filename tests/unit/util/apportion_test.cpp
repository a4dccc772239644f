#include "common/util/apportion.h"

#include <gtest/gtest.h>

#include <numeric>

namespace portico {
namespace {

TEST(Apportion, SharesSumToTheTotalWithTiesToTheLowerIndex) {
  const auto shares = largestRemainderShares(10, {1.0, 1.0, 1.0});
  EXPECT_EQ(shares, (std::vector<uint64_t>{4, 3, 3}));
  const auto uneven = largestRemainderShares(1000003, {0.7, 2.1, 5.3, 0.0});
  EXPECT_EQ(std::accumulate(uneven.begin(), uneven.end(), uint64_t(0)), 1000003u);
  EXPECT_EQ(uneven[3], 0u);
}

TEST(Apportion, CapsHoldAndNoWeightGivesNothing) {
  const auto capped = largestRemainderShares(10, {1.0, 1.0}, {2, 100});
  EXPECT_EQ(capped, (std::vector<uint64_t>{2, 8}));
  EXPECT_EQ(largestRemainderShares(5, {0.0, 0.0}), (std::vector<uint64_t>{0, 0}));
}

}  // namespace
}  // namespace portico
