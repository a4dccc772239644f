// Bounds what peers that have not authenticated can hold of the
// coordinator: an idle TCP connection needs no key, yet each holds a
// descriptor, and a few hundred left the coordinator unable to answer
// status or write an image ("Too many open files"). Three limits:
//   * a connection must finish its handshake (CURVE and the ZAP verdict)
//     within kHandshakeMs, or libzmq closes it (ZMQ_HANDSHAKE_IVL);
//   * at most kMostUnprovenPerPeer connections of one address may be
//     unproven (no message received yet) at once: a new one closes that
//     address's oldest unproven connection, which had the longest to
//     finish (a real peer finishes in milliseconds, and its request is
//     re-sent on reconnection, since libzmq keeps it queued until then);
//   * at most maxConnections in all, so that a quarter of the descriptors
//     (64 to 1024) stay free for the coordinator's own files (jobs.db,
//     photon files, images).
// The coordinator raises its soft descriptor limit to the hard one at start.
// Connections are known from the socket monitor (ConnectionLog: accepted,
// closed, each with its descriptor) and proven by their first message
// (ZMQ_SRCFD). Closing one is a shutdown(2) of its descriptor, after
// checking it is still the same peer; libzmq then closes it as a peer that left.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <string>

#include "common/util/log_throttle.h"

namespace portico {

class ConnectionGuard {
 public:
  static constexpr int kHandshakeMs = 5000;
  static constexpr size_t kMostUnprovenPerPeer = 64;
  // Kept free for the coordinator's own files: a quarter of the limit, within these.
  static constexpr uint64_t kLeastReservedDescriptors = 64, kMostReservedDescriptors = 1024;

  // Raises RLIMIT_NOFILE's soft limit to the hard one; returns the
  // connections to admit (what is left beyond the reserve).
  static size_t raiseDescriptorLimit();

  explicit ConnectionGuard(size_t maxConnections) : maxConnections_(maxConnections) {}

  void accepted(int fd);
  void closed(int fd);
  // A message arrived on `fd`: the peer passed the handshake.
  void proven(int fd);

  size_t connections() const { return connections_.size(); }

 private:
  struct Connection {
    std::string peer;   // address without the port: the limit's unit
    std::string peerWithPort;
    uint64_t order = 0;   // accept order: oldest first
    bool proven = false;
  };
  // Shuts `fd` down if it is still the connection recorded; forgets it.
  void close(int fd, const char* why);
  // The oldest unproven connection (of `peer`, or of anyone when empty); -1 if none.
  int oldestUnproven(const std::string& peer) const;

  size_t maxConnections_;
  std::map<int, Connection> connections_;
  std::map<std::string, size_t> unprovenByPeer_;
  // A message can be read before the monitor's accepted event for its connection.
  std::map<int, std::string> provenEarly_;   // descriptor -> that connection's peer and port
  uint64_t accepts_ = 0;
  LogThrottle closings_;
};

}  // namespace portico
