// Fuzz target: a photon table (8-byte records, as stored per cell and
// sent in PhotonsReply) unpacked and built into a photon map, as the worker does.
#include <cstddef>
#include <cstdint>
#include <stdexcept>

#include "tests/fuzz/fuzz_support.h"

using namespace portico;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::vector<StoredPhoton> photons;
  try {
    unpackRecords(data, size, fuzz::photonFrame(), size % 2 == 0, photons);
    fuzz::buildPhotonMap(photons);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
