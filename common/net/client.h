// A client of the coordinator (the `portico` command, tests): one DEALER
// socket, one request at a time, each answered within a timeout. With CURVE
// keys (`--keys DIR`) a client with a wrong key is never answered: the
// timeout is how it finds out.
#pragma once

#include <capnp/message.h>

#include <chrono>
#include <memory>
#include <string>
#include <zmq.hpp>

#include "common/net/message.h"

namespace portico::net {

class CoordinatorClient {
 public:
  // keysDirectory: where `portico keys generate` wrote the keys ("" for none).
  explicit CoordinatorClient(const std::string& endpoint, const std::string& keysDirectory = "",
                             std::chrono::milliseconds timeout = std::chrono::seconds(30));
  // Sends the request and returns the reply; throws std::runtime_error on
  // timeout (naming the endpoint) or when the coordinator answers with an error.
  std::unique_ptr<Decoded> request(capnp::MallocMessageBuilder& message);

  uint64_t submit(capnp::MallocMessageBuilder& submitEnvelope);
  std::string statusJson(uint64_t job);   // job 0: all jobs
  std::string cancel(uint64_t job);
  void shutdown();

 private:
  std::string endpoint_;
  std::chrono::milliseconds timeout_;
  zmq::context_t context_;
  zmq::socket_t socket_;
};

}  // namespace portico::net
