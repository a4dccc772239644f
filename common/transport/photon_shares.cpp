#include "common/transport/photon_shares.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>

#include "common/transport/sampling.h"
#include "common/util/apportion.h"

namespace portico {

std::vector<uint64_t> photonSharesOfLights(const std::vector<AreaLight>& lights, uint64_t total) {
  std::vector<Vec3> powers(lights.size());
  for (size_t i = 0; i < lights.size(); ++i) powers[i] = lights[i].power();
  return photonSharesOfPowers(powers, total);
}

std::vector<uint64_t> photonSharesOfPowers(const std::vector<Vec3>& powers, uint64_t total) {
  std::vector<double> power(powers.size());
  for (size_t i = 0; i < powers.size(); ++i) power[i] = luminance(powers[i]);
  // Lights without power (all black) share equally.
  if (!(std::accumulate(power.begin(), power.end(), 0.0) > 0)) std::fill(power.begin(), power.end(), 1.0);
  return largestRemainderShares(total, power);
}

}  // namespace portico
