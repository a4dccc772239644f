#include "common/net/endpoint_scope.h"

#include <gtest/gtest.h>

namespace portico {
namespace {

TEST(EndpointScope, LoopbackAndLocalTransportsNeedNoKeys) {
  for (const char* endpoint : {"tcp://127.0.0.1:5555", "tcp://127.0.0.1:*", "tcp://127.3.2.1:7", "tcp://localhost:5555",
                               "tcp://[::1]:5555", "ipc:///tmp/portico.sock", "inproc://coordinator"})
    EXPECT_TRUE(net::isLoopbackEndpoint(endpoint)) << endpoint;
}

TEST(EndpointScope, EverythingElseMayBeReachableFromOtherMachines) {
  for (const char* endpoint :
       {"tcp://0.0.0.0:5555", "tcp://*:5555", "tcp://0.0.0.0:*", "tcp://192.168.1.4:5555", "tcp://eth0:5555",
        "tcp://[::]:5555", "tcp://127.0.0.1.example.com:5555", "tcp://127.0.0:5555", "tcp://127.0.0.256:5555",
        "tcp://128.0.0.1:5555", "tcp://127.0.0.1", "tcp://localhost.example.com:1", "ws://127.0.0.1:5555",
        "epgm://eth0;239.192.1.1:5555", ""})
    EXPECT_FALSE(net::isLoopbackEndpoint(endpoint)) << endpoint;
}

}  // namespace
}  // namespace portico
