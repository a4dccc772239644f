#include "worker/worker_session.h"

#include "worker/deposit_region_writer.h"

#include <capnp/message.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <filesystem>
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
#include <pthread.h>
#include <ctime>
#include <sys/eventfd.h>
#include <unistd.h>

#include "common/net/message.h"
#include "common/util/resident_memory.h"
#include "worker/crash_report.h"
#include "worker/lease_load.h"
#include "worker/lease_runner.h"
#include "worker/photon_file_reader.h"

namespace portico {

namespace {
int64_t steadyMilliseconds() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}
}  // namespace

// --memory bounds the whole worker: the cache gets what is left after the
// process's own footprint (code, libraries, Embree and TBB) and room for a
// lease's messages and kernel buffers; and a load may bring the measured
// resident size up to --memory less that room (CellCache::makeRoom).
CellCache cacheFor(const WorkerOptions& options) {
  const uint64_t resident = residentBytes();
  const uint64_t leaseBuffers = uint64_t(12) << 20;
  const uint64_t leastForCells = uint64_t(4) << 20;
  if (options.memoryBytes < resident + leaseBuffers + leastForCells)
    throw std::runtime_error(fmt::format("--memory {} MiB is too small: the worker itself takes {} MiB, a lease's "
                                         "buffers {} MiB, and cells need {} MiB at least",
                                         options.memoryBytes >> 20, resident >> 20, leaseBuffers >> 20,
                                         leastForCells >> 20));
  const uint64_t budget = options.memoryBytes - resident - leaseBuffers;
  spdlog::info("--memory {} MiB: the worker itself {} MiB, a lease's buffers {} MiB, cells and photon maps {} MiB",
               options.memoryBytes >> 20, resident >> 20, leaseBuffers >> 20, budget >> 20);
  return CellCache(budget, options.memoryBytes - leaseBuffers);
}

WorkerSession::WorkerSession(WorkerOptions options)
    : options_(std::move(options)),
      cache_(cacheFor(options_)),
      chooser_(options_.calibrationPath.empty() ? CostModel::loadDefault() : CostModel::load(options_.calibrationPath)),
      leaseFinishedFd_(::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)) {
  if (leaseFinishedFd_ < 0) throw std::runtime_error("cannot create an eventfd");
  crash_report::install(leaseFinishedFd_);
  // Read now: a bad key file stops the worker at start, not at its first connection.
  if (const std::string keys = net::keysForEndpoint(options_.keysDirectory, options_.connect); !keys.empty())
    keys_ = net::loadClientKeys(keys, net::Role::Worker);
  if (!options_.cacheDirectory.empty()) mirror_ = std::make_unique<StoreMirror>(options_.cacheDirectory);
  spdlog::debug("accelerator cost model (for --accel auto): {}", chooser_.model().origin);
  LinkOptions link;
  link.endpoint = options_.connect;
  link.name = options_.name;
  link.cores = options_.threads;
  link.memoryBytes = options_.memoryBytes;
  link.tags = options_.tags;
  link.heartbeatMs = options_.heartbeatMs;
  link.livenessMs = options_.livenessMs;
  link.describeProgress = [this](wire::Heartbeat::Builder beat) {
    std::lock_guard lock(chain_.mutex);
    creditTracingCpu();
    beat.setProgress(progress_.load(std::memory_order_relaxed));
    beat.setTracingLease(chain_.running ? chain_.runningLease : 0);
  };
  link_ = std::make_unique<CoordinatorLink>(std::move(link), keys_);
}

WorkerSession::~WorkerSession() { ::close(leaseFinishedFd_); }

void WorkerSession::creditTracingCpu() {
  if (!chain_.running || !chain_.tracingClock) return;
  timespec used{};
  if (::clock_gettime(*chain_.tracingClock, &used) != 0) return;
  const int64_t ticks = (int64_t(used.tv_sec) * 1'000'000'000 + used.tv_nsec) / kCpuTickNs;
  if (ticks <= chain_.cpuTicksCredited) return;
  progress_.fetch_add(uint64_t(ticks - chain_.cpuTicksCredited), std::memory_order_relaxed);
  chain_.cpuTicksCredited = ticks;
}

FinishedLease WorkerSession::traceLease(const net::Decoded& decoded, std::optional<std::string> photonRecords) {
  FinishedLease done;
  try {
    auto assign = decoded.envelope().getAssign();
    done.lease = assign.getLease();
    const std::string store = assign.getSpec().getStore();
    done.message = runLease(cache_, chooser_, assign, std::move(photonRecords),
                            mirror_ ? mirror_->localDirectory(store) : store, options_.forwardRays, &stopLease_,
                            &progress_);
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
  return assign.getPhase() != wire::Phase::RENDER || cache_.indirectLight(photonMapKey(assign)) != nullptr;
}

// The tracing thread: traces `first`, then, while the next queued lease is
// ready to trace, that one, and so on. The chain keeps the worker busy
// between leases: handing each lease back to the main thread to start the
// next costs a wake-up and a new thread, half a millisecond or more on busy
// cores, which is a tenth of a two-worker photon pass whose leases last a
// few milliseconds. Each finished lease is handed over at once
// (leaseFinishedFd_), so its Result leaves while the next one is traced.
void WorkerSession::runChain(std::unique_ptr<net::Decoded> first, std::optional<std::string> photonRecords) {
  // Denormals cost ~100x per operation and never matter to a picture.
  _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
  _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
  crash_report::enterTracingThread();
  {
    clockid_t clock;
    std::lock_guard lock(chain_.mutex);
    chain_.cpuTicksCredited = 0;   // a new thread's clock starts at zero
    if (::pthread_getcpuclockid(::pthread_self(), &clock) == 0) chain_.tracingClock = clock;
  }
  std::unique_ptr<net::Decoded> assign = std::move(first);
  while (assign) {
    {
      std::lock_guard lock(chain_.mutex);
      chain_.runningJob = assign->envelope().getAssign().getJob();
      chain_.runningLease = assign->envelope().getAssign().getLease();
      chain_.runningSinceMs = steadyMilliseconds();
      progress_.fetch_add(1, std::memory_order_relaxed);
      stopLease_ = chain_.abandon || stopping_ || chain_.cancelledJobs.count(chain_.runningJob) != 0;
    }
    // Fault injection: the cell crashes the worker (reported, then fatal).
    if (options_.crashInLease > 0 && ++leasesStarted_ == options_.crashInLease) ::raise(SIGSEGV);
    FinishedLease done = traceLease(*assign, std::move(photonRecords));
    progress_.fetch_add(1, std::memory_order_relaxed);
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
        chain_.tracingClock.reset();   // this thread ends: its clock goes with it
      }
    }
    const uint64_t one = 1;
    (void)!::write(leaseFinishedFd_, &one, sizeof one);
  }
}

int WorkerSession::run() {
  while (!stopping_) {
    LinkEvent event = link_->receive(leaseFinishedFd_);
    if (event.kind == LinkEvent::Kind::Refused) return 2;
    if (event.kind == LinkEvent::Kind::Lost) {
      abandonLeases();   // the coordinator requeues them
      continue;
    }
    if (event.message) handle(std::move(event.message));
    uint64_t count;
    (void)!::read(leaseFinishedFd_, &count, sizeof count);   // finished leases: collected below
    reportCrashIfAny();
    failStalledLease();
    sendFinishedLeases();
    prepareQueuedLeases();
  }
  abandonLeases();
  link_->sendGoodbye();
  return stalled_ ? 1 : 0;
}

void WorkerSession::handle(std::unique_ptr<net::Decoded> decoded) {
  try {
    auto envelope = decoded->envelope();
    switch (envelope.which()) {
      case wire::Envelope::ASSIGN: onAssign(std::move(decoded)); break;
      case wire::Envelope::FILE_CHUNK: onFileChunk(envelope.getFileChunk()); break;
      case wire::Envelope::PHOTONS: onPhotons(envelope.getPhotons()); break;
      case wire::Envelope::CANCEL: onCancel(envelope.getCancel().getJob()); break;
      case wire::Envelope::SHUTDOWN: stop(); break;
      default: spdlog::warn("ignored message type {}", int(envelope.which()));
    }
  } catch (const kj::Exception& e) {
    spdlog::warn("dropped a malformed message: {}", e.getDescription().cStr());
  } catch (const std::exception& e) {
    spdlog::warn("dropped a message: {}", e.what());
  }
}

void WorkerSession::onAssign(std::unique_ptr<net::Decoded> decoded) {
  // More than the coordinator sends (kMostLeasesInFlight): refused beyond it.
  constexpr size_t kMostQueued = 12;
  std::unique_lock lock(chain_.mutex);
  if (chain_.queued.size() >= kMostQueued) {
    const size_t queuedNow = chain_.queued.size();
    lock.unlock();
    const uint64_t lease = decoded->envelope().getAssign().getLease();
    spdlog::warn("coordinator assigned lease {} with {} leases queued; refusing", lease, queuedNow);
    sendFailure(lease, "worker busy");
    return;
  }
  chain_.queued.push_back(std::move(decoded));   // started by prepareQueuedLeases
}

void WorkerSession::onFileChunk(wire::FileChunk::Reader chunk) {
  if (!preparing_ || !preparing_->waitingForFile || !mirror_) return;
  if (chunk.getStore() != preparing_->requestedStore || chunk.getPath() != preparing_->requestedFile) {
    spdlog::warn("dropped a chunk of {} of {}: asked for {}", chunk.getPath().cStr(), chunk.getStore().cStr(),
                 preparing_->requestedFile);
    return;
  }
  preparing_->waitingForFile = false;
  progress_.fetch_add(1, std::memory_order_relaxed);
  try {
    mirror_->accept(chunk);
  } catch (const std::exception& e) {
    failLease(e.what());
    return;
  }
  advanceLease();
}

void WorkerSession::onPhotons(wire::PhotonsReply::Reader reply) {
  if (!preparing_ || !preparing_->waitingForPhotons) return;
  auto assign = preparing_->assign->envelope().getAssign();
  if (reply.getJob() != assign.getJob() || reply.getCell() != assign.getCell()) return;
  preparing_->waitingForPhotons = false;
  progress_.fetch_add(1, std::memory_order_relaxed);
  if (reply.hasError() && reply.getError().size() > 0) {
    failLease(reply.getError().cStr());
    return;
  }
  if (namesPhotonFile(reply)) {
    std::string why;
    auto records = readPhotonFile(reply, why);
    if (!records) {
      // Asked again, bytes included: the coordinator reads the file itself
      // (and runs the photon pass again if it is damaged).
      spdlog::warn("job {} cell {}: cannot read the photon file ({}); its photons come over the wire", reply.getJob(),
                   reply.getCell(), why);
      if (!std::filesystem::exists(reply.getFile().cStr())) photonFilesUnreachable_ = true;
      preparing_->photonBytesAsked = true;
      advanceLease();
      return;
    }
    startTracing(std::move(records));
    return;
  }
  startTracing(photonTableOf(reply));
}

// The job was cancelled or failed: its leases here are dropped, the one
// being traced stops between two pieces of work, and nothing is reported
// for any of them.
void WorkerSession::onCancel(uint64_t job) {
  if (preparing_ && preparing_->assign->envelope().getAssign().getJob() == job) preparing_.reset();
  std::lock_guard lock(chain_.mutex);
  chain_.cancelledJobs.insert(job);
  std::erase_if(chain_.queued, [&](const std::unique_ptr<net::Decoded>& queued) {
    return queued->envelope().getAssign().getJob() == job;
  });
  if (chain_.running && chain_.runningJob == job) stopLease_ = true;
  spdlog::info("job {} ended: its leases here are dropped", job);
}

// With no chain tracing and none being readied, the next queued lease is
// readied here (one that fails at once, e.g. on a missing file, makes way
// for the one after it).
void WorkerSession::prepareQueuedLeases() {
  for (;;) {
    {
      std::lock_guard lock(chain_.mutex);
      if (preparing_ || chain_.running || chain_.queued.empty()) return;
      preparing_.emplace();
      preparing_->assign = std::move(chain_.queued.front());
      chain_.queued.pop_front();
    }
    cache_.beginLease();   // what the previous lease pinned may go now
    advanceLease();
  }
}

// A new lease waits for what it lacks, one request at a time: the store's
// files (--cache-dir), then the cell's photons (render phase); then it
// starts tracing.
void WorkerSession::advanceLease() {
  auto assign = preparing_->assign->envelope().getAssign();
  const std::string store = assign.getSpec().getStore();
  if (mirror_) {
    std::optional<std::string> file;
    try {
      // The lease's own cell, then its more cells (Assign.moreCells).
      file = mirror_->missing(store, assign.getCell());
      for (auto more : assign.getMoreCells()) {
        if (file) break;
        file = mirror_->missing(store, more.getCell());
      }
    } catch (const std::exception& e) {
      failLease(e.what());
      return;
    }
    if (file) {
      capnp::MallocMessageBuilder message;
      auto fetch = message.initRoot<wire::Envelope>().initFetchFile();
      fetch.setStore(store);
      fetch.setPath(*file);
      fetch.setOffset(mirror_->receivedBytes(store, *file));
      link_->send(message);
      preparing_->waitingForFile = true;
      preparing_->requestedStore = store;
      preparing_->requestedFile = *file;
      return;
    }
  }
  if (assign.getPhase() == wire::Phase::RENDER && !cache_.indirectLight(photonMapKey(assign))) {
    capnp::MallocMessageBuilder message;
    auto fetch = message.initRoot<wire::Envelope>().initFetchPhotons();
    fetch.setJob(assign.getJob());
    fetch.setCell(assign.getCell());
    fetch.setReadsPhotonFile(!photonFilesUnreachable_ && !preparing_->photonBytesAsked);
    link_->send(message);
    preparing_->waitingForPhotons = true;
    return;
  }
  startTracing(std::nullopt);
}

void WorkerSession::startTracing(std::optional<std::string> photonRecords) {
  {
    std::lock_guard lock(chain_.mutex);
    chain_.running = true;
    chain_.runningSinceMs = steadyMilliseconds();   // and again by the chain, for each lease it takes
  }
  if (tracing_.valid()) tracing_.wait();   // the previous chain's thread, done but for its return
  tracing_ = std::async(std::launch::async,
                        [this, assign = std::move(preparing_->assign), p = std::move(photonRecords)]() mutable {
                          runChain(std::move(assign), std::move(p));
                        });
  preparing_.reset();
}

void WorkerSession::failLease(const std::string& why) {
  const uint64_t lease = preparing_->assign->envelope().getAssign().getLease();
  spdlog::error("lease {} failed: {}", lease, why);
  sendFailure(lease, why);
  preparing_.reset();
}

void WorkerSession::sendFailure(uint64_t lease, const std::string& why, std::optional<uint32_t> failedCell) {
  capnp::MallocMessageBuilder message;
  auto failure = message.initRoot<wire::Envelope>().initFailure();
  failure.setLease(lease);
  failure.setMessage(why);
  if (failedCell) failure.setFailedCell(*failedCell);
  link_->send(message);
}

// Finished leases: their Results (or failures) go out.
void WorkerSession::sendFinishedLeases() {
  std::deque<FinishedLease> finished;
  {
    std::lock_guard lock(chain_.mutex);
    finished.swap(chain_.finished);
  }
  for (FinishedLease& done : finished) {
    // Its deposits written into the job's photon file (deposit_region_writer.h)
    // are on disk before its Result names them.
    // A write that failed (a full disk) sends them in the Result instead.
    std::string writeError;
    DepositRegionWriter::Unwritten unwritten;
    const bool written = depositRegionWriter().finish(done.lease, writeError, &unwritten);
    if (done.stopped) {
      spdlog::info("lease {} stopped midway", done.lease);
      continue;
    }
    try {
      if (!done.error.empty()) throw std::runtime_error(done.error);
      if (!written) sendDepositsInResult(done.message->getRoot<wire::Envelope>().getResult(), unwritten);
      if (options_.crashAfterLeases > 0 && leasesReported_ + 1 >= options_.crashAfterLeases) {
        // Fault injection: die holding a finished lease, as a crash
        // mid-lease would; the coordinator must requeue it.
        spdlog::warn("fault injection: exiting with lease {} unreported", done.lease);
        std::_Exit(3);
      }
      link_->sendFlat(*done.message);
      ++leasesReported_;
    } catch (const std::exception& e) {
      spdlog::error("lease {} failed: {}", done.lease, e.what());
      sendFailure(done.lease, e.what(), done.failedCell);
    } catch (const kj::Exception& e) {
      sendFailure(done.lease, fmt::format("malformed lease: {}", e.getDescription().cStr()));
    }
  }
}

// The tracing thread crashed in its lease: the cell's doing, said before
// dying, so that the coordinator counts it against the cell.
void WorkerSession::reportCrashIfAny() {
  const int signal = crash_report::pendingSignal();
  if (!signal) return;
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

// A lease that outlives --lease-limit-s is stuck, most likely in a read
// that does not return (a FIFO, a hung network file system): said to the
// coordinator, which counts it against the cell and leases the work again,
// and the worker leaves (its supervisor starts it anew).
void WorkerSession::failStalledLease() {
  uint64_t lease;
  int64_t since;
  {
    std::lock_guard lock(chain_.mutex);
    if (!chain_.running) return;
    lease = chain_.runningLease;
    since = chain_.runningSinceMs;
  }
  const int64_t ranMs = steadyMilliseconds() - since;
  if (ranMs < int64_t(options_.leaseLimitSeconds) * 1000) return;
  const std::string why = fmt::format("still tracing after {} s (--lease-limit-s): stuck, most likely in a read that "
                                      "does not return (a hung file system?)",
                                      ranMs / 1000);
  spdlog::error("lease {}: {}; the worker leaves", lease, why);
  sendFailure(lease, why);
  stalled_ = true;
  stop();   // Goodbye: the coordinator takes its other leases back
}

void WorkerSession::joinTracingThread(const char* why) {
  if (!tracing_.valid()) return;
  constexpr auto kMostStopWait = std::chrono::seconds(10);
  if (tracing_.wait_for(kMostStopWait) == std::future_status::ready) return;
  uint64_t lease;
  {
    std::lock_guard lock(chain_.mutex);
    lease = chain_.runningLease;
  }
  spdlog::error("{}: lease {} did not stop within {} s (stuck in a read that does not return?); exiting without it",
                why, lease, kMostStopWait.count());
  link_->sendGoodbye();
  std::this_thread::sleep_for(std::chrono::milliseconds(300));   // libzmq's I/O thread sends it
  std::_Exit(1);
}

void WorkerSession::abandonLeases() {
  {
    std::lock_guard lock(chain_.mutex);
    chain_.queued.clear();
    chain_.abandon = true;
    stopLease_ = true;
  }
  joinTracingThread(stopping_ ? "leaving" : "abandoning its leases");
  preparing_.reset();
  std::lock_guard lock(chain_.mutex);
  std::string ignored;
  for (const FinishedLease& done : chain_.finished) depositRegionWriter().finish(done.lease, ignored);
  chain_.finished.clear();
  chain_.abandon = false;
  chain_.running = false;
  chain_.tracingClock.reset();
  chain_.cancelledJobs.clear();
}

}  // namespace portico
