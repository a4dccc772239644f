#include "common/net/zap_authenticator.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <zmq_addon.hpp>

#include "common/net/ipc_peer.h"


namespace portico::net {

namespace {
const char* const kZapEndpoint = "inproc://zeromq.zap.01";

std::string text(const zmq::message_t& frame) { return std::string(static_cast<const char*>(frame.data()), frame.size()); }
}  // namespace

ZapAuthenticator::ZapAuthenticator(zmq::context_t& context, const ServerKeys& keys) : ZapAuthenticator(context) {
  authorized_ = keys.authorized;
  keysDirectory_ = keys.directory;
}

ZapAuthenticator::ZapAuthenticator(zmq::context_t& context, uid_t owner) : ZapAuthenticator(context) {
  owner_ = owner;
}

ZapAuthenticator::ZapAuthenticator(zmq::context_t& context) : socket_(context, zmq::socket_type::rep) {
  socket_.set(zmq::sockopt::linger, 0);
  // Bound here, on the caller's thread, so the handler exists before the
  // caller binds its server socket; the thread then owns the socket.
  socket_.bind(kZapEndpoint);
  thread_ = std::thread([this] { serve(); });
}

ZapAuthenticator::~ZapAuthenticator() {
  stopping_ = true;
  thread_.join();
}

void ZapAuthenticator::serve() {
  while (!stopping_) {
    zmq::pollitem_t items[] = {{socket_.handle(), 0, ZMQ_POLLIN, 0}};
    try {
      zmq::poll(items, 1, std::chrono::milliseconds(100));
      if (!(items[0].revents & ZMQ_POLLIN)) continue;
      std::vector<zmq::message_t> request;
      if (!zmq::recv_multipart(socket_, std::back_inserter(request), zmq::recv_flags::dontwait)) continue;
      answer(request);
    } catch (const zmq::error_t& e) {
      // No exception leaves the thread: a failed request is refused by
      // libzmq's timeout; the handler keeps serving.
      if (e.num() == ETERM) return;
      if (e.num() != EINTR) spdlog::error("authentication handler: {}", e.what());
    }
  }
}

void ZapAuthenticator::answer(const std::vector<zmq::message_t>& request) {
  // Request: version, request id, domain, address, identity, mechanism, credentials...
  const bool wellFormed = request.size() >= 6 && text(request[0]) == "1.0";
  std::string status = "400", statusText = "refused", userId;
  if (!wellFormed) {
    spdlog::warn("authentication handler: dropped a malformed ZAP request of {} frames", request.size());
  } else {
    const std::string address = text(request[3]), mechanism = text(request[5]);
    std::string why, throttleKey = mechanism;
    std::optional<Role> role;
    std::string who;
    if (mechanism == "CURVE" && request.size() >= 7 && !owner_) {
      throttleKey = z85FromBinaryKey(request[6].data(), request[6].size());
      role = admitCurve(throttleKey, why);
      who = "key:" + throttleKey;
    } else if (mechanism == "NULL" && owner_) {
      throttleKey = address;
      role = admitByUid(address, why);
      if (const std::optional<uid_t> uid = ipcPeerUid(address)) who = fmt::format("uid:{}", *uid);
    } else {
      why = fmt::format("mechanism {} (the coordinator requires {})", mechanism, owner_ ? "NULL on ipc://" : "CURVE");
    }
    if (role) {
      status = "200";
      statusText = "OK";
      userId = zapUserId(Peer{*role, who});
    } else {
      logRefusal(throttleKey, address, why);
    }
  }
  const std::string requestId = request.size() > 1 ? text(request[1]) : std::string();
  std::vector<zmq::const_buffer> reply{zmq::buffer(std::string_view("1.0")), zmq::buffer(requestId),
                                       zmq::buffer(status),  zmq::buffer(statusText),
                                       zmq::buffer(userId),  zmq::const_buffer()};
  (void)zmq::send_multipart(socket_, reply);
}

std::optional<Role> ZapAuthenticator::admitCurve(const std::string& key, std::string& why) const {
  if (auto it = authorized_.find(key); it != authorized_.end()) return it->second;
  why = fmt::format("key {} is in none of {}/{{client,worker,operator}}.public", key, keysDirectory_);
  return std::nullopt;
}

std::optional<Role> ZapAuthenticator::admitByUid(const std::string& address, std::string& why) const {
  const std::optional<uid_t> uid = ipcPeerUid(address);
  if (!uid) {
    why = "its credentials are unknown (not an ipc:// peer)";
    return std::nullopt;
  }
  if (*uid == *owner_ || *uid == 0) return Role::Operator;
  why = fmt::format("uid {} is not this coordinator's user (uid {}): without --keys it serves only its own user "
                    "and root",
                    *uid, *owner_);
  return std::nullopt;
}

void ZapAuthenticator::logRefusal(const std::string& key, const std::string& address, const std::string& why) {
  if (const auto leftOut = refusals_.admit(key))
    spdlog::warn("refused a connection from {}: {} (ZAP status 400){}", address, why, leftOutSuffix(*leftOut));
}

}  // namespace portico::net
