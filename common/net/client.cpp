#include "common/net/client.h"

#include <fmt/format.h>

#include <cerrno>
#include <filesystem>
#include <stdexcept>

#include "common/net/curve_keys.h"
#include "common/net/endpoint_scope.h"

namespace portico::net {

CoordinatorClient::CoordinatorClient(const std::string& endpoint, const std::string& keysDirectory,
                                     std::chrono::milliseconds timeout, Role role)
    : endpoint_(endpoint), timeout_(timeout), context_(1), socket_(context_, zmq::socket_type::dealer) {
  socket_.set(zmq::sockopt::linger, 200);
  socket_.set(zmq::sockopt::maxmsgsize, int64_t(kMaxFrameBytes));
  if (isIpv6Endpoint(endpoint)) socket_.set(zmq::sockopt::ipv6, true);
  if (const std::string keys = keysForEndpoint(keysDirectory, endpoint); !keys.empty()) {
    // An operator's folder holds operator.secret alone: it may do what a client does.
    namespace fs = std::filesystem;
    if (role == Role::Client && !fs::exists(fs::path(keys) / "client.secret") &&
        fs::exists(fs::path(keys) / "operator.secret"))
      role = Role::Operator;
    applyClientKeys(socket_, loadClientKeys(keys, role));
  }
  socket_.connect(endpoint);
}

std::unique_ptr<Decoded> CoordinatorClient::request(capnp::MallocMessageBuilder& message, bool resend) {
  // A late answer to an earlier, resent request is not this one's.
  for (zmq::message_t stale; socket_.recv(stale, zmq::recv_flags::dontwait);) {
  }
  const zmq::message_t frame = encode(message);
  // A DEALER whose handshake was refused has no peer left, and a blocking
  // send would wait forever: fail at once instead.
  const auto sendOnce = [&] { return socket_.send(zmq::buffer(frame.data(), frame.size()), zmq::send_flags::dontwait); };
  if (!sendOnce() && !resend)
    throw std::runtime_error(
        fmt::format("cannot send to {}: the coordinator refused this connection (wrong --keys?)", endpoint_));
  constexpr auto kResendInterval = std::chrono::seconds(2);
  const auto deadline = std::chrono::steady_clock::now() + timeout_;
  auto nextResend = std::chrono::steady_clock::now() + kResendInterval;
  for (;;) {
    const auto now = std::chrono::steady_clock::now();
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now);
    // A refused CURVE handshake is silent by design (no oracle for key
    // guessing): from here it looks like a coordinator that is down.
    if (left.count() <= 0)
      throw std::runtime_error(fmt::format("no answer from {} within {:g} s: wrong --keys, or coordinator down",
                                           endpoint_, timeout_.count() / 1000.0));
    if (resend && now >= nextResend) {
      (void)sendOnce();
      nextResend = now + kResendInterval;
    }
    zmq::pollitem_t items[] = {{socket_.handle(), 0, ZMQ_POLLIN, 0}};
    try {
      zmq::poll(items, 1, resend ? std::min(left, std::chrono::milliseconds(250)) : left);
    } catch (const zmq::error_t& e) {
      if (e.num() != EINTR) throw;
      continue;   // a signal (Ctrl-C): the answer still comes; the caller decides what the signal means
    }
    if (!(items[0].revents & ZMQ_POLLIN)) continue;
    zmq::message_t frame;
    if (!socket_.recv(frame, zmq::recv_flags::dontwait)) continue;
    auto decoded = std::make_unique<Decoded>(frame);
    auto which = decoded->envelope().which();
    if (which == wire::Envelope::HEARTBEAT) continue;   // not ours; workers' traffic only
    if (which == wire::Envelope::ERROR)
      throw std::runtime_error(fmt::format("coordinator at {}: {}", endpoint_, decoded->envelope().getError().cStr()));
    return decoded;
  }
}

uint64_t CoordinatorClient::submit(capnp::MallocMessageBuilder& submitEnvelope) {
  auto reply = request(submitEnvelope);
  if (reply->envelope().which() != wire::Envelope::SUBMIT_REPLY)
    throw std::runtime_error("coordinator sent an unexpected reply to Submit");
  auto answer = reply->envelope().getSubmitReply();
  if (answer.getError().size()) throw std::runtime_error(fmt::format("job refused: {}", answer.getError().cStr()));
  return answer.getJob();
}

std::string CoordinatorClient::statusReplyJson(capnp::MallocMessageBuilder& message, const char* what, bool resend) {
  auto reply = request(message, resend);
  if (reply->envelope().which() != wire::Envelope::STATUS_REPLY)
    throw std::runtime_error(fmt::format("coordinator sent an unexpected reply to {}", what));
  return reply->envelope().getStatusReply().getJson();
}

std::string CoordinatorClient::statusJson(uint64_t job) {
  capnp::MallocMessageBuilder message;
  message.initRoot<wire::Envelope>().initStatus().setJob(job);
  return statusReplyJson(message, "Status", true);
}

std::string CoordinatorClient::cancel(uint64_t job) {
  capnp::MallocMessageBuilder message;
  message.initRoot<wire::Envelope>().initCancel().setJob(job);
  return statusReplyJson(message, "Cancel", false);
}

std::string CoordinatorClient::setPriority(uint64_t job, int32_t priority) {
  capnp::MallocMessageBuilder message;
  auto request = message.initRoot<wire::Envelope>().initPriority();
  request.setJob(job);
  request.setPriority(priority);
  return statusReplyJson(message, "Priority", false);
}

std::unique_ptr<Decoded> CoordinatorClient::fetchImage(uint64_t job) {
  capnp::MallocMessageBuilder message;
  message.initRoot<wire::Envelope>().initFetchImage().setJob(job);
  auto reply = request(message, true);
  if (reply->envelope().which() != wire::Envelope::IMAGE)
    throw std::runtime_error("coordinator sent an unexpected reply to FetchImage");
  if (reply->envelope().getImage().getError().size())
    throw std::runtime_error(fmt::format("coordinator at {}: {}", endpoint_, reply->envelope().getImage().getError().cStr()));
  return reply;
}

std::string CoordinatorClient::jobDetailJson(uint64_t job) {
  capnp::MallocMessageBuilder message;
  message.initRoot<wire::Envelope>().initJobDetail().setJob(job);
  auto reply = request(message, true);
  if (reply->envelope().which() != wire::Envelope::JOB_DETAIL_REPLY)
    throw std::runtime_error("coordinator sent an unexpected reply to JobDetail");
  return reply->envelope().getJobDetailReply().getJson();
}

std::unique_ptr<Decoded> CoordinatorClient::fetchPreview(uint64_t job, uint32_t maxSide) {
  capnp::MallocMessageBuilder message;
  auto request = message.initRoot<wire::Envelope>().initFetchPreview();
  request.setJob(job);
  request.setMaxSide(maxSide);
  auto reply = this->request(message, true);
  if (reply->envelope().which() != wire::Envelope::PREVIEW)
    throw std::runtime_error("coordinator sent an unexpected reply to FetchPreview");
  if (reply->envelope().getPreview().getError().size())
    throw std::runtime_error(fmt::format("coordinator at {}: {}", endpoint_, reply->envelope().getPreview().getError().cStr()));
  return reply;
}

void CoordinatorClient::shutdown() {
  capnp::MallocMessageBuilder message;
  message.initRoot<wire::Envelope>().setShutdown();
  (void)socket_.send(encode(message), zmq::send_flags::dontwait);
}

}  // namespace portico::net
