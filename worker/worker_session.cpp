#include "worker/worker_session.h"

#include <capnp/message.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <deque>
#include <fstream>
#include <future>
#include <optional>
#include <thread>
#include <xmmintrin.h>
#include <pmmintrin.h>
#include <zmq.hpp>
#include <sys/eventfd.h>
#include <unistd.h>

#include "common/net/message.h"
#include "worker/lease_runner.h"

namespace portico {

namespace {
int64_t steadyMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// Never blocks: a DEALER whose handshake was refused (a wrong CURVE key) has
// no peer left, and a blocking send would hang the loop that notices the
// silence and reconnects. What cannot be sent is lost like a dropped connection.
void sendFrame(zmq::socket_t& socket, zmq::message_t& frame) {
  if (!socket.send(frame, zmq::send_flags::dontwait)) spdlog::debug("no peer to send a {} byte message to", frame.size());
}

void send(zmq::socket_t& socket, capnp::MallocMessageBuilder& message) {
  zmq::message_t frame = net::encode(message);
  sendFrame(socket, frame);
}

void sendSimple(zmq::socket_t& socket, void (*fill)(wire::Envelope::Builder)) {
  capnp::MallocMessageBuilder message;
  fill(message.initRoot<wire::Envelope>());
  send(socket, message);
}

uint64_t residentBytes() {
  std::ifstream statm("/proc/self/statm");
  uint64_t size = 0, resident = 0;
  statm >> size >> resident;
  return resident * uint64_t(::sysconf(_SC_PAGESIZE));
}

// A lease in progress: the decoded Assign (owning its bytes) and the tracing thread.
struct ActiveLease {
  std::unique_ptr<net::Decoded> assign;
  bool waitingForPhotons = false;
  bool waitingForFile = false;
  std::future<std::unique_ptr<capnp::MallocMessageBuilder>> result;
};
}  // namespace

// --memory bounds the whole worker: the cache gets what is left after the
// process's own footprint (code, libraries, Embree and TBB) and room for a
// lease's messages and kernel buffers.
uint64_t cacheBudgetFor(const WorkerOptions& options) {
  const uint64_t resident = residentBytes();
  const uint64_t leaseBuffers = uint64_t(12) << 20;
  if (options.memoryBytes < resident + leaseBuffers + (uint64_t(4) << 20))
    throw std::runtime_error(fmt::format("--memory {} MiB is too small: the worker itself takes {} MiB, a lease's "
                                         "buffers {} MiB, and cells need room",
                                         options.memoryBytes >> 20, resident >> 20, leaseBuffers >> 20));
  return options.memoryBytes - resident - leaseBuffers;
}

WorkerSession::WorkerSession(WorkerOptions options)
    : options_(std::move(options)),
      cache_(cacheBudgetFor(options_)),
      chooser_(options_.calibrationPath.empty() ? CostModel::loadDefault() : CostModel::load(options_.calibrationPath)),
      leaseDone_(::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)) {
  if (leaseDone_ < 0) throw std::runtime_error("cannot create an eventfd");
  // Read now: a bad key file stops the worker at start, not at its first connection.
  if (!options_.keysDirectory.empty()) keys_ = net::loadClientKeys(options_.keysDirectory);
  if (!options_.cacheDirectory.empty()) mirror_ = std::make_unique<StoreMirror>(options_.cacheDirectory);
  spdlog::debug("accelerator cost model (for --accel auto): {}", chooser_.model().origin);
}

WorkerSession::~WorkerSession() { ::close(leaseDone_); }

std::future<std::unique_ptr<capnp::MallocMessageBuilder>> WorkerSession::startLease(
    wire::Assign::Reader assign, std::optional<std::vector<StoredPhoton>> photons) {
  return std::async(std::launch::async, [this, assign, p = std::move(photons)]() mutable {
    // Denormals cost ~100x per operation and never matter to a picture.
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
    struct Notify {
      int fd;
      ~Notify() {
        const uint64_t one = 1;
        (void)!::write(fd, &one, sizeof one);
      }
    } notify{leaseDone_};
    const std::string store = assign.getSpec().getStore();
    return runLease(cache_, chooser_, assign, std::move(p), mirror_ ? mirror_->localDirectory(store) : store,
                    options_.forwardRays);
  });
}

int WorkerSession::run() {
  zmq::context_t context(1);
  int leasesDone = 0;
  int backoffMs = 250;
  while (!stopping_) {
    zmq::socket_t socket(context, zmq::socket_type::dealer);
    socket.set(zmq::sockopt::linger, 0);
    socket.set(zmq::sockopt::maxmsgsize, int64_t(net::kMaxFrameBytes));
    if (keys_) net::applyClientKeys(socket, *keys_);
    socket.connect(options_.connect);
    {
      capnp::MallocMessageBuilder message;
      auto hello = message.initRoot<wire::Envelope>().initHello();
      hello.setVersion(wire::PROTOCOL_VERSION);
      hello.setName(options_.name);
      hello.setCores(options_.threads);
      hello.setMemoryBytes(options_.memoryBytes);
      send(socket, message);
    }
    int64_t lastHeard = steadyMs(), lastSent = steadyMs();
    bool welcomed = false;
    uint64_t coordinatorMaxFrame = 0;   // 0: not announced (an older coordinator)
    std::optional<ActiveLease> lease;
    // Leases that came while one runs: the coordinator sends the next lease
    // before this one ends (WorkerInfo::kLeasesInFlight), so that it is
    // here the moment the tracing thread is free.
    std::deque<std::unique_ptr<net::Decoded>> queued;
    constexpr size_t kMostQueued = 4;   // more than the coordinator sends: refuse beyond it
    bool reconnect = false;
    const auto sendFailure = [&](uint64_t leaseId, const std::string& why) {
      capnp::MallocMessageBuilder message;
      auto failure = message.initRoot<wire::Envelope>().initFailure();
      failure.setLease(leaseId);
      failure.setMessage(why);
      send(socket, message);
    };
    const auto failLease = [&](const std::string& why) {
      const uint64_t leaseId = lease->assign->envelope().getAssign().getLease();
      spdlog::error("lease {} failed: {}", leaseId, why);
      sendFailure(leaseId, why);
      lease.reset();
    };
    // A new lease waits for what it lacks, one request at a time: the
    // store's files (--cache-dir), then the cell's photons (render phase);
    // then it starts tracing.
    const auto advanceLease = [&]() {
      auto assign = lease->assign->envelope().getAssign();
      if (mirror_) {
        std::optional<std::string> file;
        try {
          file = mirror_->missing(assign.getSpec().getStore(), assign.getCell());
        } catch (const std::exception& e) {
          failLease(e.what());
          return;
        }
        if (file) {
          capnp::MallocMessageBuilder message;
          auto fetch = message.initRoot<wire::Envelope>().initFetchFile();
          fetch.setStore(assign.getSpec().getStore());
          fetch.setPath(*file);
          fetch.setOffset(mirror_->receivedBytes(assign.getSpec().getStore(), *file));
          send(socket, message);
          lease->waitingForFile = true;
          return;
        }
      }
      if (assign.getPhase() == wire::Phase::RENDER && !cache_.photonMap(assign.getJob(), assign.getCell())) {
        capnp::MallocMessageBuilder message;
        auto fetch = message.initRoot<wire::Envelope>().initFetchPhotons();
        fetch.setJob(assign.getJob());
        fetch.setCell(assign.getCell());
        send(socket, message);
        lease->waitingForPhotons = true;
        return;
      }
      lease->result = startLease(assign, std::nullopt);
    };

    while (!stopping_ && !reconnect) {
      // The eventfd wakes the loop the moment a lease finishes.
      zmq::pollitem_t items[] = {{socket.handle(), 0, ZMQ_POLLIN, 0}, {nullptr, leaseDone_, ZMQ_POLLIN, 0}};
      try {
        zmq::poll(items, 2, std::chrono::milliseconds(100));
      } catch (const zmq::error_t& e) {
        if (e.num() == EINTR) continue;   // a signal: the loop condition decides
        throw;
      }
      // The eventfd is written as the lease's function returns, a moment
      // before its future is ready: then wait for the future, don't poll again.
      bool leaseFinished = false;
      if (items[1].revents & ZMQ_POLLIN) {
        uint64_t count;
        (void)!::read(leaseDone_, &count, sizeof count);
        leaseFinished = true;
      }
      const int64_t now = steadyMs();
      if (items[0].revents & ZMQ_POLLIN) {
        zmq::message_t frame;
        while (socket.recv(frame, zmq::recv_flags::dontwait)) {
          lastHeard = steadyMs();
          try {
            net::Decoded decoded(frame);
            auto envelope = decoded.envelope();
            switch (envelope.which()) {
              case wire::Envelope::WELCOME:
                welcomed = true;
                coordinatorMaxFrame = envelope.getWelcome().getMaxFrameBytes();
                backoffMs = 250;
                spdlog::info("connected to {}", options_.connect);
                sendSimple(socket, [](wire::Envelope::Builder e) { e.setReady(); });
                lastSent = steadyMs();
                break;
              case wire::Envelope::HEARTBEAT: break;
              case wire::Envelope::ASSIGN: {
                if (queued.size() >= kMostQueued) {
                  spdlog::warn("coordinator assigned lease {} with {} leases queued; refusing",
                               envelope.getAssign().getLease(), queued.size());
                  sendFailure(envelope.getAssign().getLease(), "worker busy");
                  break;
                }
                queued.push_back(std::make_unique<net::Decoded>(frame));   // started below
                break;
              }
              case wire::Envelope::FILE_CHUNK: {
                if (!lease || !lease->waitingForFile || !mirror_) break;
                lease->waitingForFile = false;
                try {
                  mirror_->accept(envelope.getFileChunk());
                } catch (const std::exception& e) {
                  failLease(e.what());
                  break;
                }
                advanceLease();
                break;
              }
              case wire::Envelope::PHOTONS: {
                if (!lease || !lease->waitingForPhotons) break;
                auto assign = lease->assign->envelope().getAssign();
                auto reply = envelope.getPhotons();
                if (reply.getJob() != assign.getJob() || reply.getCell() != assign.getCell()) break;
                if (reply.hasError() && reply.getError().size() > 0) {
                  lease->waitingForPhotons = false;
                  failLease(reply.getError().cStr());
                  break;
                }
                // Room for the decoded photons before decoding them (24-byte records).
                uint64_t records = 0;
                for (auto batch : reply.getBatches()) records += batch.size() / 24;
                cache_.makeRoom(records * sizeof(StoredPhoton));
                auto photons = decodePhotons(reply, assign.getSpec().getGather() > 0);
                lease->waitingForPhotons = false;
                lease->result = startLease(assign, std::move(photons));
                break;
              }
              case wire::Envelope::ERROR:
                spdlog::error("coordinator refused: {}", envelope.getError().cStr());
                if (!welcomed) return 2;
                break;
              case wire::Envelope::SHUTDOWN: stopping_ = true; break;
              default: spdlog::warn("ignored message type {}", int(envelope.which()));
            }
          } catch (const kj::Exception& e) {
            spdlog::warn("dropped a malformed message: {}", e.getDescription().cStr());
          } catch (const std::exception& e) {
            spdlog::warn("dropped a message: {}", e.what());
          }
        }
      }

      if (lease && lease->result.valid() &&
          (leaseFinished || lease->result.wait_for(std::chrono::seconds(0)) == std::future_status::ready)) {
        const uint64_t leaseId = lease->assign->envelope().getAssign().getLease();
        try {
          auto message = lease->result.get();
          if (options_.crashAfterLeases > 0 && leasesDone + 1 >= options_.crashAfterLeases) {
            // Fault injection: die holding a finished lease, as a crash
            // mid-lease would; the coordinator must requeue it.
            spdlog::warn("fault injection: exiting with lease {} unreported", leaseId);
            std::_Exit(3);
          }
          zmq::message_t frame = net::encode(*message, net::Encoding::Flat);
          // libzmq would drop a longer frame and the connection with it, and
          // the lease would come back forever: report it as a failure instead.
          if (coordinatorMaxFrame && frame.size() > coordinatorMaxFrame)
            throw std::runtime_error(fmt::format(
                "result of {} bytes is over the coordinator's {} byte message limit; lower its --lease-rays",
                frame.size(), coordinatorMaxFrame));
          sendFrame(socket, frame);
          ++leasesDone;
        } catch (const std::exception& e) {
          spdlog::error("lease {} failed: {}", leaseId, e.what());
          sendFailure(leaseId, e.what());
        } catch (const kj::Exception& e) {
          sendFailure(leaseId, fmt::format("malformed lease: {}", e.getDescription().cStr()));
        }
        lastSent = steadyMs();
        lease.reset();
      }

      // The next queued lease starts as soon as none runs (one that fails
      // at once, e.g. on a missing file, makes way for the one after it).
      while (!lease && !queued.empty()) {
        lease.emplace();
        lease->assign = std::move(queued.front());
        queued.pop_front();
        cache_.beginLease();   // what the previous lease pinned may go now
        advanceLease();
      }
      if (now - lastSent >= options_.heartbeatMs) {
        sendSimple(socket, [](wire::Envelope::Builder e) { e.setHeartbeat(); });
        lastSent = now;
      }
      if (now - lastHeard > options_.livenessMs) {
        if (welcomed)
          spdlog::warn("coordinator silent for {} ms; reconnecting in {} ms", now - lastHeard, backoffMs);
        else   // a refused CURVE handshake looks exactly like this
          spdlog::warn("no answer from {} within {:.0f} s: wrong --keys, or coordinator down; retrying in {} ms",
                       options_.connect, (now - lastHeard) / 1000.0, backoffMs);
        // A lease in flight is abandoned: the coordinator requeues it.
        if (lease && lease->result.valid()) lease->result.wait();
        std::this_thread::sleep_for(std::chrono::milliseconds(backoffMs));
        backoffMs = std::min(backoffMs * 2, 30000);
        reconnect = true;
      }
    }
    if (!reconnect) {
      if (lease && lease->result.valid()) lease->result.wait();
      sendSimple(socket, [](wire::Envelope::Builder e) { e.setGoodbye(); });
    }
  }
  return 0;
}

}  // namespace portico
