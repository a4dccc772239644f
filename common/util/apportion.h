// Largest-remainder apportionment: `total` shared out by weight in whole
// units that sum exactly to `total` (as far as the caps allow). Photons among
// lights, lights among rooms, triangles among rooms all use it.
#pragma once

#include <cstdint>
#include <vector>

namespace portico {

// Each share is floor(total * w / sum(w)), at most caps[i] (no cap when
// `caps` is empty); the units left go one each to the largest remainders,
// ties to the lower index. All zeros when the weights sum to zero or less.
std::vector<uint64_t> largestRemainderShares(uint64_t total, const std::vector<double>& weights,
                                             const std::vector<uint64_t>& caps = {});

}  // namespace portico
