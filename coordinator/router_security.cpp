#include "coordinator/router_security.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <stdexcept>

#include "common/net/curve_keys.h"
#include "common/net/endpoint_scope.h"

namespace portico {

void requireKeysBeyondLoopback(const std::string& listen, const std::string& keysDirectory) {
  if (keysDirectory.empty() && !net::isLoopbackEndpoint(listen))
    throw std::runtime_error(fmt::format(
        "refusing to listen on {} without --keys: only loopback (127.x, localhost, [::1]) and ipc:// are open "
        "without CURVE keys (write some with `portico keys generate DIR`)",
        listen));
}

std::string bindableEndpoint(const std::string& listen) {
  const std::string prefix = "tcp://localhost:";
  if (listen.rfind(prefix, 0) == 0) return "tcp://127.0.0.1:" + listen.substr(prefix.size());
  return listen;
}

RouterSecurity::RouterSecurity(zmq::context_t& context, zmq::socket_t& router, const std::string& listen,
                               const std::string& keysDirectory, uint64_t maxFrameBytes) {
  // libzmq drops a longer frame before buffering it, and closes that connection.
  router.set(zmq::sockopt::maxmsgsize, static_cast<int64_t>(maxFrameBytes));
  const bool ipc = listen.rfind("ipc://", 0) == 0;
  inproc_ = listen.rfind("inproc://", 0) == 0;
  ownersApart_ = !keysDirectory.empty() && !inproc_;
  if (!keysDirectory.empty() || (!ipc && !inproc_)) {
    const std::string directory = keysDirectory.empty() ? net::ensureDefaultKeys() : keysDirectory;
    const net::ServerKeys keys = net::loadServerKeys(directory);
    zap_ = std::make_unique<net::ZapAuthenticator>(context, keys);   // bound before the router binds
    net::applyServerKeys(router, keys);
    size_t counts[3] = {0, 0, 0};
    for (const auto& [key, role] : keys.authorized) ++counts[int(role)];
    spdlog::info("CURVE on{}: coordinator key {}; admits {} client, {} worker and {} operator keys from {}",
                 keysDirectory.empty() ? " (no --keys: this user's keys)" : "", keys.server.publicKey,
                 counts[int(net::Role::Client)], counts[int(net::Role::Worker)], counts[int(net::Role::Operator)],
                 directory);
  } else if (ipc) {
    zap_ = std::make_unique<net::ZapAuthenticator>(context, ::geteuid());
    // Without a ZAP domain libzmq skips the handler for the NULL mechanism.
    router.set(zmq::sockopt::zap_domain, "portico");
    spdlog::info("no --keys on ipc://: only uid {} and root may connect", ::geteuid());
  }
  // A connection that has not finished its handshake by then is closed: an
  // idle one costs nothing to open and holds a descriptor.
  router.set(zmq::sockopt::handshake_ivl, ConnectionGuard::kHandshakeMs);
  net::ConnectionLog::Listener listener;
  if (listen.rfind("tcp://", 0) == 0) {
    guard_ = std::make_unique<ConnectionGuard>(ConnectionGuard::raiseDescriptorLimit());
    listener.accepted = [this](int fd) { guard_->accepted(fd); };
    listener.closed = [this](int fd) { guard_->closed(fd); };
  }
  connections_ = std::make_unique<net::ConnectionLog>(context, router, "coordinator", std::move(listener));
}

std::optional<net::Peer> RouterSecurity::peerOf(zmq::message_t& frame) const {
  if (inproc_) return net::Peer{net::Role::Operator, "in-process"};
  if (guard_) {
    // The connection's descriptor (ZMQ_SRCFD: deprecated, still what libzmq 4.3 offers).
    const int fd = zmq_msg_get(frame.handle(), ZMQ_SRCFD);
    if (fd >= 0) guard_->proven(fd);
  }
  const char* userId = zmq_msg_gets(frame.handle(), "User-Id");
  if (!userId) return std::nullopt;
  return net::peerOfZapUserId(userId);
}

}  // namespace portico
