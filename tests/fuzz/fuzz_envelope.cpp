// Fuzz target: one ZeroMQ frame through the decoder every program uses
// (net::Decoded), then every field of whichever Envelope variant it holds,
// and the rays and photon tables inside as the worker reads them.
#include <cstddef>
#include <cstdint>

#include "common/net/message.h"
#include "tests/fuzz/fuzz_support.h"

using namespace portico;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const zmq::message_t frame(data, size);
  // A malformed frame must end as one of these two, caught and logged by
  // the coordinator and the worker; anything else is a bug.
  try {
    net::Decoded decoded(frame);
    const auto envelope = decoded.envelope();
    (void)fuzz::readEverything(capnp::toDynamic(envelope));
    std::vector<StoredPhoton> photons;
    switch (envelope.which()) {
      case wire::Envelope::ASSIGN:
        for (const auto batch : envelope.getAssign().getBatches())
          if (batch.isRays()) (void)fuzz::readRays(batch.getRays());
        for (const auto more : envelope.getAssign().getMoreCells())
          for (const auto batch : more.getBatches())
            if (batch.isRays()) (void)fuzz::readRays(batch.getRays());
        break;
      case wire::Envelope::RESULT:
        for (const auto crossing : envelope.getResult().getCrossings()) (void)fuzz::readRays(crossing.getRays());
        for (const auto deposits : envelope.getResult().getDeposits())
          unpackRecords(deposits.getRecords().begin(), deposits.getRecords().size(), fuzz::photonFrame(), true,
                        photons);
        break;
      case wire::Envelope::PHOTONS:   // the worker's photonTableOf, then runLease's decoding
        for (const auto blob : envelope.getPhotons().getBatches())
          unpackRecords(blob.begin(), blob.size(), fuzz::photonFrame(), false, photons);
        fuzz::buildPhotonMap(photons);
        break;
      default: break;
    }
  } catch (const std::runtime_error&) {
  } catch (const kj::Exception&) {
  }
  return 0;
}
