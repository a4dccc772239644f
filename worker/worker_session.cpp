#include "worker/worker_session.h"

#include <capnp/message.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <csignal>
#include <cstring>
#include <deque>
#include <fstream>
#include <mutex>
#include <future>
#include <optional>
#include <thread>
#include <xmmintrin.h>
#include <pmmintrin.h>
#include <zmq.hpp>
#include <sys/eventfd.h>
#include <unistd.h>

#include "common/net/message.h"
#include "worker/crash_report.h"
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

// A lease the main thread readies before it is traced: it may wait for the
// store's files (--cache-dir) or the cell's photons (render phase).
struct PreparingLease {
  std::unique_ptr<net::Decoded> assign;
  bool waitingForPhotons = false;
  bool waitingForFile = false;
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
  crash_report::install(leaseDone_);
  // Read now: a bad key file stops the worker at start, not at its first connection.
  if (const std::string keys = net::keysForEndpoint(options_.keysDirectory, options_.connect); !keys.empty())
    keys_ = net::loadClientKeys(keys, net::Role::Worker);
  if (!options_.cacheDirectory.empty()) mirror_ = std::make_unique<StoreMirror>(options_.cacheDirectory);
  spdlog::debug("accelerator cost model (for --accel auto): {}", chooser_.model().origin);
}

WorkerSession::~WorkerSession() { ::close(leaseDone_); }

FinishedLease WorkerSession::traceLease(const net::Decoded& decoded, std::optional<std::string> photonRecords) {
  FinishedLease done;
  try {
    auto assign = decoded.envelope().getAssign();
    done.lease = assign.getLease();
    const std::string store = assign.getSpec().getStore();
    done.message = runLease(cache_, chooser_, assign, std::move(photonRecords),
                            mirror_ ? mirror_->localDirectory(store) : store, options_.forwardRays, &stopLease_);
  } catch (const TracingStopped&) {
    done.stopped = true;
  } catch (const MoreCellError& e) {
    done.error = e.what();
    done.failedCell = e.cell;
  } catch (const std::exception& e) {
    done.error = e.what();
  } catch (const kj::Exception& e) {
    done.error = fmt::format("malformed lease: {}", e.getDescription().cStr());
  }
  return done;
}

// Whether a queued lease can be traced with nothing from the main thread:
// no store files to fetch, and in the render phase its cell's photon map
// already cached. Called on the tracing thread, which alone touches the
// cache while a chain runs.
bool WorkerSession::readyToTrace(const net::Decoded& decoded) {
  if (mirror_) return false;
  auto assign = decoded.envelope().getAssign();
  return assign.getPhase() != wire::Phase::RENDER || cache_.indirectLight(assign.getJob(), assign.getCell()) != nullptr;
}

// The tracing thread: traces `first`, then, while the next queued lease is
// ready to trace, that one, and so on. Handing each lease back to the main
// thread to start the next (a wake-up of the main thread, then a new
// thread) left the worker idle between leases, half a millisecond or more
// when the cores were busy: a tenth of a two-worker photon pass, whose
// leases last a few milliseconds. Each finished lease is handed over at
// once (leaseDone_), so its Result leaves while the next one is traced.
void WorkerSession::runChain(std::unique_ptr<net::Decoded> first, std::optional<std::string> photonRecords) {
  // Denormals cost ~100x per operation and never matter to a picture.
  _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
  _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
  crash_report::enterTracingThread();
  std::unique_ptr<net::Decoded> assign = std::move(first);
  while (assign) {
    {
      std::lock_guard lock(chain_.mutex);
      chain_.runningJob = assign->envelope().getAssign().getJob();
      chain_.runningLease = assign->envelope().getAssign().getLease();
      stopLease_ = chain_.abandon || stopping_ || chain_.cancelledJobs.count(chain_.runningJob) != 0;
    }
    // Fault injection: the cell crashes the worker (reported, then fatal).
    if (options_.crashInLease > 0 && ++leasesStarted_ == options_.crashInLease) ::raise(SIGSEGV);
    FinishedLease done = traceLease(*assign, std::move(photonRecords));
    photonRecords.reset();
    assign.reset();
    // What the finished lease pinned may go now; and before the readiness
    // check below, whose photon map lookup pins the map for the next lease
    // (pinned under the old lease, it could be evicted by the next lease's
    // own cell load, and the lease would fail for want of its photons).
    cache_.beginLease();
    {
      std::lock_guard lock(chain_.mutex);
      chain_.finished.push_back(std::move(done));
      std::erase_if(chain_.queued, [&](const std::unique_ptr<net::Decoded>& queued) {
        return chain_.cancelledJobs.count(queued->envelope().getAssign().getJob()) != 0;
      });
      if (!chain_.queued.empty() && !chain_.abandon && readyToTrace(*chain_.queued.front())) {
        assign = std::move(chain_.queued.front());
        chain_.queued.pop_front();
      } else {
        chain_.running = false;
      }
    }
    const uint64_t one = 1;
    (void)!::write(leaseDone_, &one, sizeof one);
  }
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
    // The lease being readied on this thread (not yet traced), and the
    // tracing thread's chain (chain_: queued leases, finished ones). The
    // coordinator sends the next lease before this one ends
    // (WorkerInfo::kLeasesInFlight), so that it is here the moment the
    // tracing thread is free.
    std::optional<PreparingLease> lease;
    std::future<void> tracing;
    {
      std::lock_guard lock(chain_.mutex);
      chain_.queued.clear();
      chain_.finished.clear();
      chain_.abandon = false;
      chain_.cancelledJobs.clear();
    }
    constexpr size_t kMostQueued = 12;   // more than the coordinator sends (kMostLeasesInFlight): refuse beyond it
    const auto startTracing = [&](std::optional<std::string> photonRecords) {
      {
        std::lock_guard lock(chain_.mutex);
        chain_.running = true;
      }
      if (tracing.valid()) tracing.wait();   // the previous chain's thread, done but for its return
      tracing = std::async(std::launch::async, [this, assign = std::move(lease->assign), p = std::move(photonRecords)]() mutable {
        runChain(std::move(assign), std::move(p));
      });
      lease.reset();
    };
    bool reconnect = false;
    bool rejoin = false;   // the coordinator restarted and does not know this worker
    const auto sendFailure = [&](uint64_t leaseId, const std::string& why,
                                 std::optional<uint32_t> failedCell = std::nullopt) {
      capnp::MallocMessageBuilder message;
      auto failure = message.initRoot<wire::Envelope>().initFailure();
      failure.setLease(leaseId);
      failure.setMessage(why);
      if (failedCell) failure.setFailedCell(*failedCell);
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
          // The lease's own cell, then its more cells (Assign.moreCells).
          file = mirror_->missing(assign.getSpec().getStore(), assign.getCell());
          for (auto more : assign.getMoreCells()) {
            if (file) break;
            file = mirror_->missing(assign.getSpec().getStore(), more.getCell());
          }
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
      if (assign.getPhase() == wire::Phase::RENDER && !cache_.indirectLight(assign.getJob(), assign.getCell())) {
        capnp::MallocMessageBuilder message;
        auto fetch = message.initRoot<wire::Envelope>().initFetchPhotons();
        fetch.setJob(assign.getJob());
        fetch.setCell(assign.getCell());
        send(socket, message);
        lease->waitingForPhotons = true;
        return;
      }
      startTracing(std::nullopt);
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
      if (items[1].revents & ZMQ_POLLIN) {   // leases finished: collected below
        uint64_t count;
        (void)!::read(leaseDone_, &count, sizeof count);
      }
      if (const int signal = crash_report::pendingSignal()) {
        // The tracing thread crashed in its lease: the cell's doing, said
        // before dying, so that the coordinator counts it against the cell.
        uint64_t crashedLease;
        {
          std::lock_guard lock(chain_.mutex);
          crashedLease = chain_.runningLease;
        }
        const std::string why = fmt::format("the worker crashed tracing it ({})", strsignal(signal));
        spdlog::error("lease {}: {}; exiting", crashedLease, why);
        sendFailure(crashedLease, why);
        std::this_thread::sleep_for(std::chrono::milliseconds(300));   // libzmq's I/O thread sends it
        crash_report::dieOf(signal);
      }
      const int64_t now = steadyMs();
      if (items[0].revents & ZMQ_POLLIN) {
        zmq::message_t frame;
        while (socket.recv(frame, zmq::recv_flags::dontwait)) {
          lastHeard = steadyMs();
          try {
            auto decoded = std::make_unique<net::Decoded>(std::move(frame));   // read in place
            auto envelope = decoded->envelope();
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
                std::unique_lock lock(chain_.mutex);
                if (chain_.queued.size() >= kMostQueued) {
                  const size_t queuedNow = chain_.queued.size();
                  lock.unlock();
                  spdlog::warn("coordinator assigned lease {} with {} leases queued; refusing",
                               envelope.getAssign().getLease(), queuedNow);
                  sendFailure(envelope.getAssign().getLease(), "worker busy");
                  break;
                }
                chain_.queued.push_back(std::move(decoded));   // started below
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
                auto records = photonTableOf(reply);
                lease->waitingForPhotons = false;
                startTracing(std::move(records));
                break;
              }
              case wire::Envelope::ERROR:
                if (welcomed && std::string_view(envelope.getError().cStr()) == net::kUnknownWorkerError) {
                  rejoin = true;
                  break;
                }
                spdlog::error("coordinator refused: {}", envelope.getError().cStr());
                if (!welcomed) return 2;
                break;
              case wire::Envelope::CANCEL: {
                // The job was cancelled or failed: its leases here are
                // dropped, the one being traced stops between two pieces
                // of work, and nothing is reported for any of them.
                const uint64_t job = envelope.getCancel().getJob();
                if (lease && lease->assign->envelope().getAssign().getJob() == job) lease.reset();
                std::lock_guard lock(chain_.mutex);
                chain_.cancelledJobs.insert(job);
                std::erase_if(chain_.queued, [&](const std::unique_ptr<net::Decoded>& queued) {
                  return queued->envelope().getAssign().getJob() == job;
                });
                if (chain_.running && chain_.runningJob == job) stopLease_ = true;
                spdlog::info("job {} ended: its leases here are dropped", job);
                break;
              }
              case wire::Envelope::SHUTDOWN: stop(); break;
              default: spdlog::warn("ignored message type {}", int(envelope.which()));
            }
          } catch (const kj::Exception& e) {
            spdlog::warn("dropped a malformed message: {}", e.getDescription().cStr());
          } catch (const std::exception& e) {
            spdlog::warn("dropped a message: {}", e.what());
          }
        }
      }

      // Finished leases: their Results (or failures) go out.
      std::deque<FinishedLease> finished;
      bool tracingNow;
      {
        std::lock_guard lock(chain_.mutex);
        finished.swap(chain_.finished);
        tracingNow = chain_.running;
      }
      for (FinishedLease& done : finished) {
        if (done.stopped) {
          spdlog::info("lease {} stopped midway", done.lease);
          continue;
        }
        try {
          if (!done.error.empty()) throw std::runtime_error(done.error);
          if (options_.crashAfterLeases > 0 && leasesDone + 1 >= options_.crashAfterLeases) {
            // Fault injection: die holding a finished lease, as a crash
            // mid-lease would; the coordinator must requeue it.
            spdlog::warn("fault injection: exiting with lease {} unreported", done.lease);
            std::_Exit(3);
          }
          zmq::message_t frame = net::encode(*done.message, net::Encoding::Flat);
          // libzmq would drop a longer frame and the connection with it, and
          // the lease would come back forever: report it as a failure instead.
          if (coordinatorMaxFrame && frame.size() > coordinatorMaxFrame)
            throw std::runtime_error(fmt::format(
                "result of {} bytes is over the coordinator's {} byte message limit; lower its --lease-rays",
                frame.size(), coordinatorMaxFrame));
          sendFrame(socket, frame);
          ++leasesDone;
        } catch (const std::exception& e) {
          spdlog::error("lease {} failed: {}", done.lease, e.what());
          sendFailure(done.lease, e.what(), done.failedCell);
        } catch (const kj::Exception& e) {
          sendFailure(done.lease, fmt::format("malformed lease: {}", e.getDescription().cStr()));
        }
        lastSent = steadyMs();
      }

      // With no chain tracing and none being readied, the next queued lease
      // is readied here (one that fails at once, e.g. on a missing file,
      // makes way for the one after it).
      while (!lease && !tracingNow) {
        {
          std::lock_guard lock(chain_.mutex);
          if (chain_.queued.empty()) break;
          lease.emplace();
          lease->assign = std::move(chain_.queued.front());
          chain_.queued.pop_front();
        }
        cache_.beginLease();   // what the previous lease pinned may go now
        advanceLease();
        std::lock_guard lock(chain_.mutex);
        tracingNow = chain_.running;
      }
      if (now - lastSent >= options_.heartbeatMs) {
        sendSimple(socket, [](wire::Envelope::Builder e) { e.setHeartbeat(); });
        lastSent = now;
      }
      if (rejoin) {
        spdlog::info("the coordinator at {} restarted: joining it again", options_.connect);
        // Its leases were requeued when it restarted: drop them here too.
        {
          std::lock_guard lock(chain_.mutex);
          chain_.queued.clear();
          chain_.abandon = true;
        }
        if (tracing.valid()) tracing.wait();
        reconnect = true;
      } else if (now - lastHeard > options_.livenessMs) {
        if (welcomed)
          spdlog::warn("coordinator silent for {} ms; reconnecting in {} ms", now - lastHeard, backoffMs);
        else   // a refused CURVE handshake looks exactly like this
          spdlog::warn("no answer from {} within {:.0f} s: wrong --keys, or coordinator down; retrying in {} ms",
                       options_.connect, (now - lastHeard) / 1000.0, backoffMs);
        // Leases in flight are abandoned: the coordinator requeues them.
        {
          std::lock_guard lock(chain_.mutex);
          chain_.queued.clear();
          chain_.abandon = true;
          stopLease_ = true;
        }
        if (tracing.valid()) tracing.wait();
        std::this_thread::sleep_for(std::chrono::milliseconds(backoffMs));
        backoffMs = std::min(backoffMs * 2, 30000);
        reconnect = true;
      }
    }
    if (!reconnect) {
      {
        std::lock_guard lock(chain_.mutex);
        chain_.queued.clear();
        chain_.abandon = true;
        stopLease_ = true;
      }
      if (tracing.valid()) tracing.wait();
      sendSimple(socket, [](wire::Envelope::Builder e) { e.setGoodbye(); });
    }
  }
  return 0;
}

}  // namespace portico
