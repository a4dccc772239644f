// What each role may ask of the coordinator (common/net/role.h):
//   worker    Hello, Ready, Heartbeat, Result, Failure, FetchPhotons and
//             FetchFile (of the jobs it holds leases of), Goodbye
//   client    Submit, Status, Cancel, Priority, FetchImage, JobDetail and FetchPreview
//             (the dashboard's; and Heartbeat)
//   operator  all of these, and Shutdown
// A peer admitted with no role (none is known) may ask nothing.
#pragma once

#include <optional>
#include <string>

#include "common/net/role.h"
#include "proto/wire.capnp.h"

namespace portico {

// Why a peer in `role` may not send a message of type `type`, or nothing
// when it may.
std::optional<std::string> refusalFor(std::optional<net::Role> role, wire::Envelope::Which type);

}  // namespace portico
