// Logs what libzmq does to a socket's connections behind the application's
// back (a socket monitor): connections it closed — the peer left, sent a
// frame over ZMQ_MAXMSGSIZE, or broke the protocol — and handshakes that
// failed (a peer without CURVE, or with the wrong server key). The
// application never sees those frames, so this is the only trace of them.
#pragma once

#include <functional>
#include <string>
#include <zmq.hpp>

#include "common/util/log_throttle.h"

namespace portico::net {

class ConnectionLog {
 public:
  // Told of each connection accepted and closed, with its descriptor.
  struct Listener {
    std::function<void(int fd)> accepted, closed;
  };
  // Attach before binding `watched`. `name` makes the inproc endpoint unique.
  ConnectionLog(zmq::context_t& context, zmq::socket_t& watched, const std::string& name, Listener listener = {});
  // Logs every event waiting; never blocks. Call from the socket's own loop.
  void drain();

 private:
  zmq::socket_t events_;
  Listener listener_;
  // A peer retrying a failing handshake would write a line per attempt.
  LogThrottle throttle_;
};

}  // namespace portico::net
