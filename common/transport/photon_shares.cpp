#include "common/transport/photon_shares.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>

#include "common/transport/sampling.h"

namespace portico {

std::vector<uint64_t> photonSharesOfLights(const std::vector<AreaLight>& lights, uint64_t total) {
  std::vector<double> power(lights.size());
  for (size_t i = 0; i < lights.size(); ++i) power[i] = luminance(lights[i].power());
  const double sum = std::accumulate(power.begin(), power.end(), 0.0);
  std::vector<uint64_t> share(lights.size());
  std::vector<std::pair<double, size_t>> remainders;
  uint64_t given = 0;
  for (size_t i = 0; i < lights.size(); ++i) {
    const double exact = sum > 0 ? total * power[i] / sum : double(total) / lights.size();
    share[i] = static_cast<uint64_t>(std::floor(exact));
    given += share[i];
    remainders.push_back({exact - share[i], i});
  }
  std::sort(remainders.begin(), remainders.end(),
            [](const auto& a, const auto& b) { return a.first != b.first ? a.first > b.first : a.second < b.second; });
  for (size_t k = 0; given < total && !remainders.empty(); ++k, ++given) share[remainders[k % remainders.size()].second]++;
  return share;
}

}  // namespace portico
