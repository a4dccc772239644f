#include "coordinator/router_security.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

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

RouterSecurity::RouterSecurity(zmq::context_t& context, zmq::socket_t& router, const std::string& keysDirectory,
                               uint64_t maxFrameBytes) {
  // libzmq drops a longer frame before buffering it, and closes that connection.
  router.set(zmq::sockopt::maxmsgsize, static_cast<int64_t>(maxFrameBytes));
  if (!keysDirectory.empty()) {
    const net::ServerKeys keys = net::loadServerKeys(keysDirectory);
    zap_ = std::make_unique<net::ZapAuthenticator>(context, keys);   // bound before the router binds
    net::applyServerKeys(router, keys);
    spdlog::info("CURVE on: coordinator key {}, {} client keys accepted from {}", keys.server.publicKey,
                 keys.authorizedClients.size(), keys.authorizedFile);
  }
  connections_ = std::make_unique<net::ConnectionLog>(context, router, "coordinator");
}

}  // namespace portico
