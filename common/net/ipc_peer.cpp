#include "common/net/ipc_peer.h"

#include <charconv>

namespace portico::net {

std::optional<uid_t> ipcPeerUid(const std::string& address) {
  const size_t pidColon = address.rfind(':');
  const size_t gidColon =
      pidColon == std::string::npos || pidColon == 0 ? std::string::npos : address.rfind(':', pidColon - 1);
  const size_t uidColon =
      gidColon == std::string::npos || gidColon == 0 ? std::string::npos : address.rfind(':', gidColon - 1);
  if (uidColon == std::string::npos) return std::nullopt;
  uid_t uid = 0;
  const char* first = address.data() + uidColon + 1;
  const auto [end, error] = std::from_chars(first, address.data() + gidColon, uid);
  if (error != std::errc() || end != address.data() + gidColon || end == first) return std::nullopt;
  return uid;
}

}  // namespace portico::net
