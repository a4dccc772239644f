// Who a peer of the coordinator is, and so what it may ask for. The
// coordinator learns a peer's role from the key it authenticated with
// (ROLE.public, common/net/curve_keys.h) or, on an ipc:// socket without
// keys, from the peer's uid (its own user and root are operators).
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace portico::net {

enum class Role {
  Client,     // submits, cancels and queries jobs, fetches their images
  Worker,     // leases cell work, returns results, fetches its leases' files and photons
  Operator,   // everything above, and shuts the coordinator down
};

inline constexpr Role kAllRoles[] = {Role::Client, Role::Worker, Role::Operator};

constexpr std::string_view roleName(Role role) {
  switch (role) {
    case Role::Client: return "client";
    case Role::Worker: return "worker";
    case Role::Operator: return "operator";
  }
  return "?";
}

inline std::optional<Role> roleNamed(std::string_view name) {
  for (Role role : kAllRoles)
    if (roleName(role) == name) return role;
  return std::nullopt;
}

// An admitted peer: its role and who it is, "key:Z85" (the CURVE public
// key it proved it holds) or "uid:N" (an ipc:// peer's user); the
// coordinator records who submitted each job as its owner.
struct Peer {
  Role role = Role::Client;
  std::string who;
};

// The ZAP User-Id that carries a Peer from the authentication handler to
// the coordinator's messages: "ROLE WHO".
inline std::string zapUserId(const Peer& peer) { return std::string(roleName(peer.role)) + " " + peer.who; }
inline std::optional<Peer> peerOfZapUserId(std::string_view userId) {
  const size_t space = userId.find(' ');
  const std::optional<Role> role = roleNamed(userId.substr(0, space));
  if (!role) return std::nullopt;
  return Peer{*role, space == std::string_view::npos ? std::string() : std::string(userId.substr(space + 1))};
}

}  // namespace portico::net
