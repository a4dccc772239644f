// Who is at the other end of an ipc:// connection. libzmq reads the peer's
// credentials with SO_PEERCRED (for the side that connected: those of the
// process that listens) and appends ":uid:gid:pid" to the peer's address,
// which the coordinator's ZAP handler sees and every message received
// carries as its "Peer-Address" property.
#pragma once

#include <sys/types.h>

#include <optional>
#include <string>

namespace portico::net {

// The uid of an ipc:// peer address ("...:uid:gid:pid"); none when the
// address carries no credentials (tcp://, or unreadable).
std::optional<uid_t> ipcPeerUid(const std::string& address);

}  // namespace portico::net
