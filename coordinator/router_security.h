// What stands between the coordinator's ROUTER socket and its peers: who
// may connect, in which role (common/net/role.h), a frame size limit sized
// to legitimate messages, and a log of the connections libzmq dropped on
// its own, and limits on connections that have not authenticated
// (coordinator/connection_guard.h). Three ways in:
//   --keys DIR     CURVE; a ZAP handler admits the keys of DIR's
//                  {client,worker,operator}.public, each in its role;
//   ipc:// alone   a ZAP handler admits the coordinator's own user and root
//                  (peer credentials of the Unix socket), as operators;
//   tcp:// alone   (loopback only) CURVE with the per-user keys of
//                  net::defaultKeysDirectory(), generated on first use: the
//                  same user's workers and clients find them, other users
//                  cannot read them.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <zmq.hpp>

#include "common/net/connection_log.h"
#include "common/net/role.h"
#include "common/net/zap_authenticator.h"
#include "coordinator/connection_guard.h"

namespace portico {

// Throws std::runtime_error (one line, naming the endpoint) when `listen`
// may be reachable from other machines and no keys are given.
void requireKeysBeyondLoopback(const std::string& listen, const std::string& keysDirectory);

// tcp://localhost:PORT as libzmq binds it (it reads "localhost" as an
// interface name): tcp://127.0.0.1:PORT. Other endpoints are returned as given.
std::string bindableEndpoint(const std::string& listen);

class RouterSecurity {
 public:
  // Configures `router` before it binds to `listen`. Throws
  // std::runtime_error naming the file when a key file is bad.
  RouterSecurity(zmq::context_t& context, zmq::socket_t& router, const std::string& listen,
                 const std::string& keysDirectory, uint64_t maxFrameBytes);
  // The role of the peer that sent `frame` and who it is (its key or uid),
  // from what the ZAP handler admitted it as; none when it was admitted
  // without a role. Its connection has passed the handshake (ConnectionGuard).
  std::optional<net::Peer> peerOf(zmq::message_t& frame) const;
  // Whether the coordinator serves several users, each with keys of their
  // own (--keys): then a client sees and steers only its own jobs in full
  // (docs/security.md). Without --keys only this user's own keys or uid get
  // in, and every peer is the same user.
  bool ownersApart() const { return ownersApart_; }
  // Call from the serving loop: logs connections libzmq closed or refused.
  void logConnectionEvents() { connections_->drain(); }

 private:
  std::unique_ptr<net::ZapAuthenticator> zap_;
  std::unique_ptr<ConnectionGuard> guard_;   // tcp:// only (ipc:// admits only local users)
  std::unique_ptr<net::ConnectionLog> connections_;
  bool inproc_ = false;   // the same process: every peer is an operator
  bool ownersApart_ = false;
};

}  // namespace portico
