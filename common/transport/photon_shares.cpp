#include "common/transport/photon_shares.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>

#include "common/transport/sampling.h"
#include "common/util/apportion.h"

namespace portico {

std::vector<uint64_t> photonSharesOfLights(const std::vector<AreaLight>& lights, uint64_t total) {
  std::vector<double> power(lights.size());
  for (size_t i = 0; i < lights.size(); ++i) power[i] = luminance(lights[i].power());
  // Lights without power (all black) share equally.
  if (!(std::accumulate(power.begin(), power.end(), 0.0) > 0)) std::fill(power.begin(), power.end(), 1.0);
  return largestRemainderShares(total, power);
}

}  // namespace portico
