#include "common/net/connection_log.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cstring>
#include <stdexcept>

namespace portico::net {

namespace {
std::string describeProtocolError(uint32_t code) {
  switch (code) {
    case ZMQ_PROTOCOL_ERROR_ZMTP_MECHANISM_MISMATCH:
      return "security mechanism mismatch (one side has --keys, the other not)";
    case ZMQ_PROTOCOL_ERROR_ZMTP_CRYPTOGRAPHIC:
    case ZMQ_PROTOCOL_ERROR_ZMTP_KEY_EXCHANGE:
      return "CURVE handshake failed (the peer pinned another coordinator.public)";
    default: return fmt::format("ZMTP protocol error {:#x}", code);
  }
}

// "tcp://127.0.0.1:41234" -> "tcp://127.0.0.1": one throttle key per host.
std::string hostOf(const std::string& address) {
  const size_t colon = address.rfind(':');
  return colon == std::string::npos || colon < 6 ? address : address.substr(0, colon);
}
}  // namespace

ConnectionLog::ConnectionLog(zmq::context_t& context, zmq::socket_t& watched, const std::string& name,
                             Listener listener)
    : events_(context, zmq::socket_type::pair), listener_(std::move(listener)) {
  const std::string endpoint = "inproc://portico-monitor-" + name;
  const int events = ZMQ_EVENT_ACCEPTED | ZMQ_EVENT_DISCONNECTED | ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL |
                     ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL;
  if (zmq_socket_monitor(watched.handle(), endpoint.c_str(), events) != 0)
    throw std::runtime_error(fmt::format("cannot monitor the socket: {}", zmq_strerror(zmq_errno())));
  events_.set(zmq::sockopt::linger, 0);
  events_.connect(endpoint);
}

void ConnectionLog::drain() {
  for (;;) {
    // An event is two frames: 2-byte event id + 4-byte value, then the peer's address.
    zmq::message_t header, address;
    if (!events_.recv(header, zmq::recv_flags::dontwait)) return;
    if (!header.more() || !events_.recv(address, zmq::recv_flags::dontwait) || header.size() < 6) continue;
    uint16_t event;
    uint32_t value;
    std::memcpy(&event, header.data(), sizeof event);
    std::memcpy(&value, static_cast<const char*>(header.data()) + 2, sizeof value);
    // Accepted and disconnected events carry the connection's descriptor.
    if (event == ZMQ_EVENT_ACCEPTED) {
      if (listener_.accepted) listener_.accepted(int(value));
      continue;
    }
    if (event == ZMQ_EVENT_DISCONNECTED && listener_.closed) listener_.closed(int(value));
    const std::string peer(static_cast<const char*>(address.data()), address.size());
    const std::string host = hostOf(peer);
    // One line a minute per host and kind of event (a DISCONNECTED event's value is only its fd).
    const auto leftOut =
        throttle_.admit(fmt::format("{} {} {}", event, event == ZMQ_EVENT_DISCONNECTED ? 0 : value, host));
    if (!leftOut) continue;
    switch (event) {
      case ZMQ_EVENT_DISCONNECTED:
        spdlog::info("connection from {} closed (the peer left, or ZeroMQ dropped it for a frame over the size "
                     "limit or a protocol error){}",
                     host, leftOutSuffix(*leftOut));
        break;
      case ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL:
        spdlog::warn("refused a connection from {}: {}{}", host, describeProtocolError(value), leftOutSuffix(*leftOut));
        break;
      default:
        spdlog::warn("handshake with {} failed: {} (a peer with --keys on one side only, or not portico){}", host,
                     zmq_strerror(static_cast<int>(value)), leftOutSuffix(*leftOut));
    }
  }
}

}  // namespace portico::net
