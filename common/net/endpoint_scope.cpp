#include "common/net/endpoint_scope.h"

#include <charconv>

namespace portico::net {

namespace {
// A dotted-quad IPv4 literal whose first octet is 127 (the loopback /8).
bool isLoopbackIpv4(std::string_view host) {
  int octets = 0;
  int first = -1;
  while (true) {
    unsigned value = 0;
    const auto [end, error] = std::from_chars(host.data(), host.data() + host.size(), value);
    if (error != std::errc() || end == host.data() || value > 255) return false;
    if (octets == 0) first = static_cast<int>(value);
    ++octets;
    host.remove_prefix(static_cast<size_t>(end - host.data()));
    if (host.empty()) break;
    if (host.front() != '.' || octets == 4) return false;
    host.remove_prefix(1);
  }
  return octets == 4 && first == 127;
}
}  // namespace

bool isLoopbackEndpoint(std::string_view endpoint) {
  if (endpoint.starts_with("ipc://") || endpoint.starts_with("inproc://")) return true;
  if (!endpoint.starts_with("tcp://")) return false;
  std::string_view address = endpoint.substr(6);
  const size_t colon = address.rfind(':');
  if (colon == std::string_view::npos) return false;
  const std::string_view host = address.substr(0, colon);
  return host == "localhost" || host == "[::1]" || isLoopbackIpv4(host);
}

bool isIpv6Endpoint(std::string_view endpoint) {
  return endpoint.starts_with("tcp://") && endpoint.find('[') != std::string_view::npos;
}

}  // namespace portico::net
