// Fuzz target: a packed RayBatch or JobSpec as the coordinator reads them
// back from jobs.db (net::PackedReader), the first byte choosing which.
#include <cstddef>
#include <cstdint>

#include "common/net/message.h"
#include "tests/fuzz/fuzz_support.h"

using namespace portico;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  try {
    net::PackedReader reader(data + 1, size - 1);
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
