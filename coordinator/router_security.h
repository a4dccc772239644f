// What stands between the coordinator's ROUTER socket and the network:
// loopback only unless CURVE keys are given (then a ZAP handler admits the
// listed client keys), a frame size limit sized to legitimate messages, and
// a log of the connections libzmq dropped on its own.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <zmq.hpp>

#include "common/net/connection_log.h"
#include "common/net/zap_authenticator.h"

namespace portico {

// Throws std::runtime_error (one line, naming the endpoint) when `listen`
// may be reachable from other machines and no keys are given.
void requireKeysBeyondLoopback(const std::string& listen, const std::string& keysDirectory);

class RouterSecurity {
 public:
  // Configures `router` before it binds. Throws std::runtime_error naming
  // the file when a key file is bad.
  RouterSecurity(zmq::context_t& context, zmq::socket_t& router, const std::string& keysDirectory,
                 uint64_t maxFrameBytes);
  // Call from the serving loop: logs connections libzmq closed or refused.
  void logConnectionEvents() { connections_->drain(); }

 private:
  std::unique_ptr<net::ZapAuthenticator> zap_;
  std::unique_ptr<net::ConnectionLog> connections_;
};

}  // namespace portico
