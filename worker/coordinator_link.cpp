#include "worker/coordinator_link.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <filesystem>
#include <string_view>
#include <thread>

#include "common/net/endpoint_scope.h"
#include "common/net/ipc_peer.h"

namespace portico {

namespace {
int64_t steadyMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

constexpr int kFirstBackoffMs = 250;
constexpr int kMostBackoffMs = 30000;
}  // namespace

CoordinatorLink::CoordinatorLink(LinkOptions options, std::optional<net::ClientKeys> keys)
    : options_(std::move(options)),
      keys_(std::move(keys)),
      checkPeerUid_(!keys_ && options_.endpoint.rfind("ipc://", 0) == 0),
      backoffMs_(kFirstBackoffMs) {}

// Without keys on ipc://, the coordinator is whoever listens on the socket's
// path: any local user may bind it in a folder they can write (before the
// coordinator starts, or while it restarts). Trusted only when the socket
// belongs to this user or root, in a folder no one else may change.
std::optional<std::string> CoordinatorLink::untrustedSocket() const {
  const std::string path = options_.endpoint.substr(std::string_view("ipc://").size());
  const uid_t us = ::geteuid();
  struct stat info {};
  const std::string folder = std::filesystem::path(path).parent_path().string();
  if (!folder.empty() && ::stat(folder.c_str(), &info) == 0) {
    if (info.st_uid != us && info.st_uid != 0)
      return fmt::format("its folder {} belongs to uid {}, who may put any socket there", folder, info.st_uid);
    if ((info.st_mode & S_IWOTH) && !(info.st_mode & S_ISVTX))
      return fmt::format("its folder {} is writable by every user (mode {:o}, not sticky): anyone may replace the "
                         "socket",
                         folder, info.st_mode & 07777);
  }
  if (::lstat(path.c_str(), &info) != 0) return std::nullopt;   // not there yet: libzmq retries; messages are checked
  if (!S_ISSOCK(info.st_mode)) return fmt::format("{} is not a socket", path);
  if (info.st_uid != us && info.st_uid != 0)
    return fmt::format("the socket {} belongs to uid {}, not to uid {} (this user) or root: another user may have "
                       "taken its path",
                       path, info.st_uid, us);
  return std::nullopt;
}

// The same for each message: libzmq reconnects by itself after the
// coordinator restarts, to whoever listens on the path by then, and
// SO_PEERCRED names that process's user.
std::optional<std::string> CoordinatorLink::untrustedSender(zmq::message_t& frame) const {
  const char* address = zmq_msg_gets(frame.handle(), "Peer-Address");
  const std::optional<uid_t> uid = address ? net::ipcPeerUid(address) : std::nullopt;
  if (!uid) return std::string("its credentials are unknown");
  if (*uid != ::geteuid() && *uid != 0)
    return fmt::format("it is served by uid {}, not by uid {} (this user) or root: another user may have taken the "
                       "socket's path",
                       *uid, ::geteuid());
  return std::nullopt;
}

bool CoordinatorLink::connect() {
  if (backoffDue_) {
    std::this_thread::sleep_for(std::chrono::milliseconds(backoffMs_));
    backoffMs_ = std::min(backoffMs_ * 2, kMostBackoffMs);
    backoffDue_ = false;
  }
  if (checkPeerUid_) {
    if (const auto why = untrustedSocket()) {
      spdlog::error("not connecting to {}: {}; retrying in {} ms", options_.endpoint, *why, backoffMs_);
      backoffDue_ = true;
      return false;
    }
  }
  socket_.emplace(context_, zmq::socket_type::dealer);
  socket_->set(zmq::sockopt::linger, 0);
  socket_->set(zmq::sockopt::maxmsgsize, int64_t(net::kMaxFrameBytes));
  if (net::isIpv6Endpoint(options_.endpoint)) socket_->set(zmq::sockopt::ipv6, true);
  if (keys_) net::applyClientKeys(*socket_, *keys_);
  socket_->connect(options_.endpoint);
  welcomed_ = false;
  coordinatorMaxFrame_ = 0;
  capnp::MallocMessageBuilder message;
  auto hello = message.initRoot<wire::Envelope>().initHello();
  hello.setVersion(wire::PROTOCOL_VERSION);
  hello.setName(options_.name);
  hello.setCores(options_.cores);
  hello.setMemoryBytes(options_.memoryBytes);
  auto tags = hello.initTags(static_cast<unsigned>(options_.tags.size()));
  for (size_t i = 0; i < options_.tags.size(); ++i) tags.set(static_cast<unsigned>(i), options_.tags[i]);
  send(message);
  lastHeardMs_ = steadyMs();
  return true;
}

LinkEvent CoordinatorLink::receive(int wakeFd, std::chrono::milliseconds wait) {
  if (!socket_ && !connect()) return LinkEvent{};
  if (steadyMs() - lastSentMs_ >= options_.heartbeatMs) {
    capnp::MallocMessageBuilder message;
    auto beat = message.initRoot<wire::Envelope>().initHeartbeat();
    if (options_.describeProgress) options_.describeProgress(beat);
    send(message);
  }
  LinkEvent event;
  zmq::message_t frame;
  bool received = bool(socket_->recv(frame, zmq::recv_flags::dontwait));
  if (!received) {
    // The descriptor wakes the worker the moment a lease finishes.
    zmq::pollitem_t items[] = {{socket_->handle(), 0, ZMQ_POLLIN, 0}, {nullptr, wakeFd, ZMQ_POLLIN, 0}};
    try {
      zmq::poll(items, wakeFd >= 0 ? 2 : 1, wait);
    } catch (const zmq::error_t& e) {
      if (e.num() != EINTR) throw;   // a signal: the worker's loop decides
    }
    if (items[0].revents & ZMQ_POLLIN) received = bool(socket_->recv(frame, zmq::recv_flags::dontwait));
  }
  if (received && checkPeerUid_) {
    if (const auto why = untrustedSender(frame)) {
      spdlog::error("refused the coordinator at {}: {}; reconnecting in {} ms", options_.endpoint, *why, backoffMs_);
      socket_.reset();
      backoffDue_ = true;
      welcomed_ = false;
      event.kind = LinkEvent::Kind::Lost;
      return event;
    }
  }
  if (received) {
    lastHeardMs_ = steadyMs();
    try {
      event.message = std::make_unique<net::Decoded>(std::move(frame));   // read in place
      if (!handleOwn(*event.message, event)) event.kind = LinkEvent::Kind::Message;
    } catch (const kj::Exception& e) {
      spdlog::warn("dropped a malformed message: {}", e.getDescription().cStr());
      event = LinkEvent{};
    } catch (const std::exception& e) {
      spdlog::warn("dropped a message: {}", e.what());
      event = LinkEvent{};
    }
    if (event.kind != LinkEvent::Kind::Idle) return event;
  }
  if (auto lost = checkLiveness()) return std::move(*lost);
  return LinkEvent{};
}

bool CoordinatorLink::handleOwn(const net::Decoded& decoded, LinkEvent& event) {
  auto envelope = decoded.envelope();
  switch (envelope.which()) {
    case wire::Envelope::WELCOME: {
      welcomed_ = true;
      coordinatorMaxFrame_ = envelope.getWelcome().getMaxFrameBytes();
      backoffMs_ = kFirstBackoffMs;
      spdlog::info("connected to {}", options_.endpoint);
      capnp::MallocMessageBuilder message;
      message.initRoot<wire::Envelope>().setReady();
      send(message);
      break;
    }
    case wire::Envelope::HEARTBEAT: break;
    case wire::Envelope::ERROR:
      if (welcomed_ && std::string_view(envelope.getError().cStr()) == net::kUnknownWorkerError) {
        // It restarted and does not know this worker: its leases were
        // requeued when it restarted; say Hello again at once.
        spdlog::info("the coordinator at {} restarted: joining it again", options_.endpoint);
        socket_.reset();
        event.kind = LinkEvent::Kind::Lost;
        break;
      }
      spdlog::error("coordinator refused: {}", envelope.getError().cStr());
      if (!welcomed_) event.kind = LinkEvent::Kind::Refused;
      break;
    default: return false;
  }
  event.message.reset();
  return true;
}

std::optional<LinkEvent> CoordinatorLink::checkLiveness() {
  const int64_t silentMs = steadyMs() - lastHeardMs_;
  if (!socket_ || silentMs <= options_.livenessMs) return std::nullopt;
  if (welcomed_)
    spdlog::warn("coordinator silent for {} ms; reconnecting in {} ms", silentMs, backoffMs_);
  else   // a refused CURVE handshake looks exactly like this
    spdlog::warn("no answer from {} within {:.0f} s: wrong --keys, or coordinator down; retrying in {} ms",
                 options_.endpoint, silentMs / 1000.0, backoffMs_);
  socket_.reset();
  backoffDue_ = true;
  LinkEvent event;
  event.kind = LinkEvent::Kind::Lost;
  return event;
}

// Never blocks: a DEALER whose handshake was refused (a wrong CURVE key) has
// no peer left, and a blocking send would hang the loop that notices the
// silence and reconnects.
void CoordinatorLink::sendFrame(zmq::message_t& frame) {
  if (!socket_) return;
  if (!socket_->send(frame, zmq::send_flags::dontwait))
    spdlog::debug("no peer to send a {} byte message to", frame.size());
  lastSentMs_ = steadyMs();
}

void CoordinatorLink::send(capnp::MessageBuilder& message) {
  zmq::message_t frame = net::encode(message);
  sendFrame(frame);
}

void CoordinatorLink::sendFlat(capnp::MessageBuilder& message) {
  zmq::message_t frame = net::encode(message, net::Encoding::Flat);
  // Over the limit, the lease would come back forever: it is failed instead.
  if (coordinatorMaxFrame_ && frame.size() > coordinatorMaxFrame_)
    throw std::runtime_error(fmt::format(
        "result of {} bytes is over the coordinator's {} byte message limit; lower its --lease-rays", frame.size(),
        coordinatorMaxFrame_));
  sendFrame(frame);
}

void CoordinatorLink::sendGoodbye() {
  capnp::MallocMessageBuilder message;
  message.initRoot<wire::Envelope>().setGoodbye();
  send(message);
}

}  // namespace portico
