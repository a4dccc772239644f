// Whether a ZeroMQ endpoint can be reached only from this machine: the
// coordinator listens beyond it only with CURVE keys.
#pragma once

#include <string_view>

namespace portico::net {

// True for ipc:// and inproc://, and for tcp:// on 127.x.x.x, localhost or
// [::1]. Everything else (tcp://*, tcp://0.0.0.0, an interface name, a
// host name, another transport) may be reachable from other machines.
bool isLoopbackEndpoint(std::string_view endpoint);

// True for a tcp:// endpoint on an IPv6 address ([::1], [fe80::...]): its
// socket needs ZMQ_IPV6 set, or libzmq takes the literal for an interface
// name ("No such device").
bool isIpv6Endpoint(std::string_view endpoint);

}  // namespace portico::net
