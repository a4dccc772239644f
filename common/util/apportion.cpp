#include "common/util/apportion.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <utility>

namespace portico {

std::vector<uint64_t> largestRemainderShares(uint64_t total, const std::vector<double>& weights,
                                             const std::vector<uint64_t>& caps) {
  std::vector<uint64_t> shares(weights.size(), 0);
  const double sum = std::accumulate(weights.begin(), weights.end(), 0.0);
  if (!(sum > 0)) return shares;
  const auto capOf = [&](size_t i) { return caps.empty() ? std::numeric_limits<uint64_t>::max() : caps[i]; };
  std::vector<std::pair<double, size_t>> remainders;
  uint64_t given = 0;
  for (size_t i = 0; i < weights.size(); ++i) {
    const double exact = double(total) * weights[i] / sum;
    shares[i] = std::min<uint64_t>(capOf(i), uint64_t(exact));
    given += shares[i];
    remainders.push_back({exact - double(shares[i]), i});
  }
  // Stable: equal remainders keep index order.
  std::stable_sort(remainders.begin(), remainders.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  for (size_t k = 0; given < total && k < remainders.size() * 4; ++k) {
    const size_t i = remainders[k % remainders.size()].second;
    if (shares[i] < capOf(i)) ++shares[i], ++given;
  }
  return shares;
}

}  // namespace portico
