// The worker's link to the coordinator, the zguide's Majordomo worker API:
// the worker asks for the next message and sends replies; the link says
// Hello, answers Welcome with Ready, sends heartbeats, swallows the
// coordinator's, notices its silence and reconnects with exponential
// back-off. Any message sent or received counts as a heartbeat. Without
// CURVE keys (ipc:// only: tcp:// always pins the coordinator's key), the
// coordinator must be a process of this user or root: the socket's owner
// is checked before connecting and the sender's SO_PEERCRED on every
// message, so another local user who binds the socket's path is refused.
#pragma once

#include <capnp/message.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>
#include <zmq.hpp>

#include "common/net/curve_keys.h"
#include "common/net/message.h"

namespace portico {

struct LinkOptions {
  std::string endpoint;
  std::string name;            // the worker's name in the coordinator's status
  uint32_t cores = 1;
  uint64_t memoryBytes = 0;
  std::vector<std::string> tags;   // its pools (Hello.tags)
  int heartbeatMs = 1000;
  int livenessMs = 10000;      // coordinator silence before reconnecting
  // Fills each heartbeat with how far the worker's leases have come
  // (Heartbeat.progress, tracingLease); none: both 0.
  std::function<void(wire::Heartbeat::Builder)> describeProgress;
};

// What CoordinatorLink::receive saw.
struct LinkEvent {
  enum class Kind {
    Message,   // `message` holds the next message for the worker
    Idle,      // nothing within the wait (or the wake descriptor fired)
    Lost,      // the coordinator went silent or restarted: its leases here are void; the next receive reconnects
    Refused,   // the coordinator refused the Hello: the worker must leave
  } kind = Kind::Idle;
  std::unique_ptr<net::Decoded> message;
};

class CoordinatorLink {
 public:
  CoordinatorLink(LinkOptions options, std::optional<net::ClientKeys> keys);

  // Connects first when needed (after Lost, once its back-off has passed).
  // Then returns the next message at once if one is waiting, else waits up to
  // `wait` for one or for `wakeFd` to become readable (-1: none).
  LinkEvent receive(int wakeFd, std::chrono::milliseconds wait = std::chrono::milliseconds(100));
  // Never blocks: what cannot be sent (no peer) is lost like a dropped connection.
  void send(capnp::MessageBuilder& message);
  // A flat frame (a lease's Result); throws when it is over the coordinator's
  // message limit, which would drop the frame and the connection with it.
  void sendFlat(capnp::MessageBuilder& message);
  // The worker is leaving (nothing is sent when not connected).
  void sendGoodbye();

 private:
  // False when it would not connect (an ipc:// socket it may not trust).
  bool connect();
  // Why the coordinator on ipc:// (no keys) is not trusted; none when it is.
  std::optional<std::string> untrustedSocket() const;
  std::optional<std::string> untrustedSender(zmq::message_t& frame) const;
  // The link's own messages (Welcome, Heartbeat, the coordinator's Errors);
  // false for those the worker handles.
  bool handleOwn(const net::Decoded& decoded, LinkEvent& event);
  std::optional<LinkEvent> checkLiveness();
  void sendFrame(zmq::message_t& frame);

  LinkOptions options_;
  std::optional<net::ClientKeys> keys_;
  // ipc:// without keys: the coordinator must be this user or root (no CURVE key to check it by).
  bool checkPeerUid_ = false;
  zmq::context_t context_{1};
  std::optional<zmq::socket_t> socket_;   // none: lost, to be connected again
  int backoffMs_ = 250;
  bool backoffDue_ = false;               // lost to silence: wait before the next Hello
  bool welcomed_ = false;
  uint64_t coordinatorMaxFrame_ = 0;      // 0: not announced (an older coordinator)
  int64_t lastHeardMs_ = 0, lastSentMs_ = 0;
};

}  // namespace portico
