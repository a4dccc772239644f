// A cell's photon table read by the worker itself from the job's photon
// file, where the coordinator's reply names it (PhotonsReply.file and
// extents) rather than carrying it: on a shared file system those bytes do
// not pass through the coordinator's one thread and socket.
#pragma once

#include <optional>
#include <string>

#include "proto/wire.capnp.h"

namespace portico {

// Whether the reply names where the batches lie instead of carrying them.
bool namesPhotonFile(wire::PhotonsReply::Reader reply);

// The batches' records, in order, as photonTableOf gives them; none, with
// `why`, when the file cannot be opened or read, or a batch's bytes fail
// their CRC-32C (another machine's file at that path, a damaged file): the
// worker then asks for the bytes, and the coordinator, reading them
// itself, tells a damaged file from an unreachable one.
std::optional<std::string> readPhotonFile(wire::PhotonsReply::Reader reply, std::string& why);

}  // namespace portico
