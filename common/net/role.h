// Who a peer of the coordinator is, and so what it may ask for. The
// coordinator learns a peer's role from the key it authenticated with
// (ROLE.public, common/net/curve_keys.h) or, on an ipc:// socket without
// keys, from the peer's uid (its own user and root are operators).
#pragma once

#include <optional>
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

}  // namespace portico::net
