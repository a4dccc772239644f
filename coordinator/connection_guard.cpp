#include "coordinator/connection_guard.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <sys/socket.h>

#include <algorithm>

namespace portico {

namespace {
// "IP" and "IP:port" of a TCP peer; empty when `fd` is no connected IP socket.
std::pair<std::string, std::string> peerOf(int fd) {
  sockaddr_storage address{};
  socklen_t length = sizeof address;
  if (::getpeername(fd, reinterpret_cast<sockaddr*>(&address), &length) != 0) return {};
  char host[INET6_ADDRSTRLEN] = {0};
  unsigned port = 0;
  if (address.ss_family == AF_INET) {
    const auto* v4 = reinterpret_cast<const sockaddr_in*>(&address);
    ::inet_ntop(AF_INET, &v4->sin_addr, host, sizeof host);
    port = ntohs(v4->sin_port);
  } else if (address.ss_family == AF_INET6) {
    const auto* v6 = reinterpret_cast<const sockaddr_in6*>(&address);
    ::inet_ntop(AF_INET6, &v6->sin6_addr, host, sizeof host);
    port = ntohs(v6->sin6_port);
  } else {
    return {"local", "local:" + std::to_string(fd)};
  }
  return {host, std::string(host) + ":" + std::to_string(port)};
}
}  // namespace

size_t ConnectionGuard::raiseDescriptorLimit() {
  rlimit limit{};
  if (::getrlimit(RLIMIT_NOFILE, &limit) != 0) return 768;
  if (limit.rlim_cur < limit.rlim_max) {
    const rlim_t before = limit.rlim_cur;
    limit.rlim_cur = limit.rlim_max;
    if (::setrlimit(RLIMIT_NOFILE, &limit) == 0)
      spdlog::info("descriptor limit raised from {} to {}", before, limit.rlim_cur);
    else
      ::getrlimit(RLIMIT_NOFILE, &limit);
  }
  const uint64_t soft = limit.rlim_cur == RLIM_INFINITY ? uint64_t(1) << 20 : uint64_t(limit.rlim_cur);
  const uint64_t reserve = std::clamp<uint64_t>(soft / 4, kLeastReservedDescriptors, kMostReservedDescriptors);
  return size_t(std::max<uint64_t>(16, soft > reserve ? soft - reserve : 0));
}

void ConnectionGuard::accepted(int fd) {
  if (connections_.count(fd)) closed(fd);   // its close was not seen: the descriptor was reused
  auto [peer, peerWithPort] = peerOf(fd);
  if (peer.empty()) return;   // gone already
  // Proven already if its first message was read before this event, by this very connection.
  bool provenEarly = false;
  if (const auto early = provenEarly_.find(fd); early != provenEarly_.end()) {
    provenEarly = early->second == peerWithPort;
    provenEarly_.erase(early);
  }
  Connection& connection = connections_[fd];
  connection = {peer, peerWithPort, ++accepts_, provenEarly};
  if (connection.proven) return;
  if (++unprovenByPeer_[peer] > kMostUnprovenPerPeer)
    close(oldestUnproven(peer), "more than 64 connections of one address without a finished handshake");
  if (connections_.size() > maxConnections_) {
    const int oldest = oldestUnproven("");
    close(oldest >= 0 ? oldest : fd, "the coordinator's connection limit (descriptors kept for its own files)");
  }
}

void ConnectionGuard::closed(int fd) {
  const auto it = connections_.find(fd);
  if (it == connections_.end()) return;
  if (!it->second.proven) {
    auto count = unprovenByPeer_.find(it->second.peer);
    if (count != unprovenByPeer_.end() && --count->second == 0) unprovenByPeer_.erase(count);
  }
  connections_.erase(it);
}

void ConnectionGuard::proven(int fd) {
  const auto it = connections_.find(fd);
  if (it != connections_.end() && it->second.proven) return;
  // The entry under this descriptor may be a connection libzmq closed since
  // (its event not read yet), the descriptor now another's: the peer's port tells.
  const std::string current = peerOf(fd).second;
  if (current.empty()) return;
  if (it == connections_.end() || it->second.peerWithPort != current) {
    if (provenEarly_.size() >= 4 * kMostUnprovenPerPeer) provenEarly_.clear();   // bounded
    provenEarly_[fd] = current;   // its accepted event is still to come
    return;
  }
  it->second.proven = true;
  auto count = unprovenByPeer_.find(it->second.peer);
  if (count != unprovenByPeer_.end() && --count->second == 0) unprovenByPeer_.erase(count);
}

int ConnectionGuard::oldestUnproven(const std::string& peer) const {
  int oldest = -1;
  uint64_t order = UINT64_MAX;
  for (const auto& [fd, connection] : connections_)
    if (!connection.proven && (peer.empty() || connection.peer == peer) && connection.order < order) {
      oldest = fd;
      order = connection.order;
    }
  return oldest;
}

void ConnectionGuard::close(int fd, const char* why) {
  const auto it = connections_.find(fd);
  if (it == connections_.end()) return;
  const Connection connection = it->second;
  // Events arrive late: the descriptor may be another file by now. Only
  // the very connection recorded (same peer and port) is shut down.
  if (peerOf(fd).second == connection.peerWithPort) ::shutdown(fd, SHUT_RDWR);
  closed(fd);
  if (const auto leftOut = closings_.admit(connection.peer))
    spdlog::warn("closed a connection from {} before its handshake: {}{}", connection.peer, why,
                 leftOutSuffix(*leftOut));
}

}  // namespace portico
