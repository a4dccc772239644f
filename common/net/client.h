// A client of the coordinator (the `portico` command, tests): one DEALER
// socket, one request at a time, each answered within a timeout. With CURVE
// keys (`--keys DIR`) a client with a wrong key is never answered: the
// timeout is how it finds out. Requests that change nothing (status, an
// image) are sent again every couple of seconds until answered, so one lost
// with a coordinator that restarted is not waited for in vain.
#pragma once

#include <capnp/message.h>

#include <chrono>
#include <memory>
#include <string>
#include <zmq.hpp>

#include "common/net/message.h"
#include "common/net/role.h"

namespace portico::net {

class CoordinatorClient {
 public:
  // keysDirectory: where `portico keys generate` wrote the keys ("": none
  // on ipc://, the per-user keys on tcp:// when they exist); `role`: whose
  // secret key of it to present.
  explicit CoordinatorClient(const std::string& endpoint, const std::string& keysDirectory = "",
                             std::chrono::milliseconds timeout = std::chrono::seconds(30), Role role = Role::Client);
  // Sends the request and returns the reply; throws std::runtime_error on
  // timeout (naming the endpoint) or when the coordinator answers with an
  // error. `resend`: a request that may be answered twice (it changes nothing).
  std::unique_ptr<Decoded> request(capnp::MallocMessageBuilder& message, bool resend = false);
  // Sends `message` (named `what` in errors) and returns the job status JSON
  // the coordinator answers it with (Status, Cancel, Priority).
  std::string statusReplyJson(capnp::MallocMessageBuilder& message, const char* what, bool resend);

  uint64_t submit(capnp::MallocMessageBuilder& submitEnvelope);
  std::string statusJson(uint64_t job);   // job 0: all jobs
  std::string cancel(uint64_t job);
  // A job's new priority (kMinPriority..kMaxPriority, coordinator/job_limits.h):
  // its next leases follow it. Returns the job's status JSON, as cancel.
  std::string setPriority(uint64_t job, int32_t priority);
  // A done job's encoded image; throws naming the job when it has none.
  std::unique_ptr<Decoded> fetchImage(uint64_t job);
  // The dashboard's: a job's cells and log lines (JobDetailReply's JSON),
  // and its film so far, at most maxSide pixels a side (PreviewReply; throws
  // with its error when it has none).
  std::string jobDetailJson(uint64_t job);
  std::unique_ptr<Decoded> fetchPreview(uint64_t job, uint32_t maxSide);
  void shutdown();   // needs the operator role

 private:
  std::string endpoint_;
  std::chrono::milliseconds timeout_;
  zmq::context_t context_;
  zmq::socket_t socket_;
};

}  // namespace portico::net
