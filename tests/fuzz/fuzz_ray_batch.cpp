// Fuzz target: a RayBatch or JobSpec, packed or flat, as the coordinator
// reads them back from jobs.db and its batch files (net::MessageReader). The
// first byte chooses: bit 0 the type, bit 1 whether the bytes are first
// copied to an aligned buffer (a flat message is then read in place).
#include <cstddef>
#include <cstdint>
#include <string>

#include "common/net/message.h"
#include "tests/fuzz/fuzz_support.h"

using namespace portico;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  try {
    std::string aligned;
    const uint8_t* bytes = data + 1;
    if (data[0] & 2) {
      aligned.assign(reinterpret_cast<const char*>(data + 1), size - 1);
      bytes = reinterpret_cast<const uint8_t*>(aligned.data());
    }
    net::MessageReader reader(bytes, size - 1);
    if (data[0] & 1) {
      (void)fuzz::readEverything(capnp::toDynamic(reader.root<wire::JobSpec>()));
      return 0;
    }
    const auto batch = reader.root<wire::RayBatch>();
    (void)fuzz::readEverything(capnp::toDynamic(batch));
    if (batch.isRays()) (void)fuzz::readRays(batch.getRays());
  } catch (const std::runtime_error&) {
  } catch (const kj::Exception&) {
  }
  return 0;
}
