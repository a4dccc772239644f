// What a render lease shades indirect light with in one cell: its photon
// map and, with precomputed irradiance, the cache built from it. Built once
// per (job, cell) on a worker and cached together (CellCache).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "common/transport/irradiance_cache.h"
#include "common/transport/photon_map.h"

namespace portico {

struct IndirectLight {
  PhotonMap photons;
  std::optional<IrradianceCache> irradiance;   // set when final gathering reads precomputed irradiance

  uint64_t bytes() const { return photons.bytes() + (irradiance ? irradiance->bytes() : 0); }
};

}  // namespace portico
