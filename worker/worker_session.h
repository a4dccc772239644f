// The worker's service: leases in, results out. Tracing runs on a second
// thread so that messages (and heartbeats) keep flowing during a long lease.
#pragma once

#include <capnp/message.h>

#include <atomic>
#include <cstdint>
#include <deque>
#include <mutex>
#include <future>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "common/net/curve_keys.h"
#include "common/net/message.h"
#include "proto/wire.capnp.h"

#include "worker/accelerator_choice.h"
#include "worker/cell_cache.h"
#include "worker/coordinator_link.h"
#include "worker/store_mirror.h"

namespace portico {

struct WorkerOptions {
  std::string connect = "tcp://127.0.0.1:5555";
  std::string name;
  uint64_t memoryBytes = uint64_t(2) << 30;
  uint32_t threads = 1;
  // Its pools (`--tag`, common/job/worker_tags.h): jobs that require tags
  // come only to workers having all of them.
  std::vector<std::string> tags;
  int heartbeatMs = 1000;
  int livenessMs = 10000;      // coordinator silence before reconnecting
  // Fault injection for recovery tests: exit abruptly, without reporting it,
  // when the Nth lease is finished (0: never).
  int crashAfterLeases = 0;
  // Fault injection: a fatal signal (SIGSEGV) on the tracing thread as the
  // Nth lease starts, as a cell that crashes the worker (0: never).
  int crashInLease = 0;
  std::string keysDirectory;   // CURVE keys ("" for none)
  // Fetch scene stores from the coordinator into this directory instead of
  // reading them where the job says ("" : read them in place).
  std::string cacheDirectory;
  // The cost model's calibration for `--accel auto` ("": CostModel::defaultPath()
  // when it exists, else the built-in one).
  std::string calibrationPath;
  // Most rays a lease traces in neighbour cells this worker already holds
  // (at least as many as the lease's own work); 0: every crossing goes back.
  int64_t forwardRays = 20000;
  // A lease still tracing after this long is failed and the worker leaves:
  // its thread is stuck (a read that never returns, on a hung file system),
  // and heartbeats alone would keep its work held for good.
  int leaseLimitSeconds = 600;
};

// A traced lease: its Result, or why it failed.
struct FinishedLease {
  uint64_t lease = 0;
  std::unique_ptr<capnp::MallocMessageBuilder> message;
  std::string error;
  std::optional<uint32_t> failedCell;   // one of the lease's more cells, if that is what failed
  bool stopped = false;                 // given up midway (job cancelled, worker stopping): nothing to report
};

// The worker: "next message -> handle it -> reply", over a CoordinatorLink
// that hides the handshake, heartbeats and reconnection. Leases are readied
// on the main thread (store files, photons) and traced on a second one.
class WorkerSession {
 public:
  explicit WorkerSession(WorkerOptions options);
  ~WorkerSession();
  // Serves until stop(), a Shutdown message, or a refused Hello. Returns the exit code.
  int run();
  // Safe in a signal handler: the lease being traced stops too, between two
  // small pieces of work, so the worker leaves within about a second.
  void stop() {
    stopping_ = true;
    stopLease_ = true;
  }

 private:
  // A lease the main thread readies before it is traced: it may wait for the
  // store's files (--cache-dir) or the cell's photons (render phase).
  struct PreparingLease {
    std::unique_ptr<net::Decoded> assign;
    bool waitingForPhotons = false;
    bool photonBytesAsked = false;   // the photon file it named could not be read: the bytes were asked for
    bool waitingForFile = false;
    std::string requestedStore, requestedFile;   // the FetchFile sent: a chunk must answer it
  };

  // The main thread: the coordinator's messages.
  void handle(std::unique_ptr<net::Decoded> decoded);
  void onAssign(std::unique_ptr<net::Decoded> decoded);
  void onFileChunk(wire::FileChunk::Reader chunk);
  void onPhotons(wire::PhotonsReply::Reader reply);
  void onCancel(uint64_t job);
  // The main thread: leases in and out.
  void prepareQueuedLeases();
  void advanceLease();
  void startTracing(std::optional<std::string> photonRecords);
  void failLease(const std::string& why);
  void sendFinishedLeases();
  void sendFailure(uint64_t lease, const std::string& why, std::optional<uint32_t> failedCell = std::nullopt);
  void reportCrashIfAny();
  void failStalledLease();
  // Waits for the tracing thread, asked to stop, for a bounded time; a
  // thread stuck in a system call makes the worker exit instead of hanging.
  void joinTracingThread(const char* why);
  // Stops the chain, waits for it, and forgets every lease (the coordinator
  // requeues them): the link was lost, or the worker is leaving.
  void abandonLeases();

  // The tracing thread.
  FinishedLease traceLease(const net::Decoded& assign, std::optional<std::string> photonRecords);
  bool readyToTrace(const net::Decoded& assign);
  // `first`, then each queued lease ready to trace.
  void runChain(std::unique_ptr<net::Decoded> first, std::optional<std::string> photonRecords);

  WorkerOptions options_;
  std::unique_ptr<StoreMirror> mirror_;
  std::optional<net::ClientKeys> keys_;
  CellCache cache_;
  AcceleratorChooser chooser_;
  int leaseFinishedFd_;   // eventfd: written for each finished lease
  std::unique_ptr<CoordinatorLink> link_;
  // The lease being readied on the main thread (not yet traced). The
  // coordinator sends the next lease before this one ends
  // (WorkerInfo::kLeasesInFlight), so that it is here the moment the
  // tracing thread is free.
  std::optional<PreparingLease> preparing_;
  // The coordinator's photon files cannot be opened from here (another
  // machine): photon tables are asked for with their bytes from then on.
  bool photonFilesUnreachable_ = false;
  std::future<void> tracing_;   // the tracing thread of the current chain
  int leasesReported_ = 0;      // Results sent (--crash-after-leases)
  // Shared by the main thread and the tracing thread, under `mutex`.
  struct Chain {
    std::mutex mutex;
    std::deque<std::unique_ptr<net::Decoded>> queued;   // Assigns not started, oldest first
    std::deque<FinishedLease> finished;                 // traced, not yet reported
    bool running = false;                               // a chain is tracing (it alone uses the cache)
    bool abandon = false;                               // reconnecting or leaving: take no more
    uint64_t runningJob = 0;                            // the job of the lease being traced
    uint64_t runningLease = 0;                          // and the lease
    int64_t runningSinceMs = 0;                         // steady clock: when it started
    std::set<uint64_t> cancelledJobs;                   // told by the coordinator (Cancel)
    // The tracing thread's CPU clock (set by the thread as it starts) and
    // how many of its kCpuTick it has been credited in progress_.
    std::optional<clockid_t> tracingClock;
    int64_t cpuTicksCredited = 0;
  } chain_;
  // A tracing thread that uses the CPU is moving, even in a step that counts
  // nothing (reading a cell, building its accelerator or photon map); one
  // stuck in a read that never returns uses none. Each 100 ms of its CPU
  // time counts as progress (creditTracingCpu, at every heartbeat).
  static constexpr int64_t kCpuTickNs = 100'000'000;
  void creditTracingCpu();   // under chain_.mutex
  std::atomic<bool> stopping_{false};
  // The lease being traced gives up (runLease's stop): its job was
  // cancelled, or the worker is leaving or reconnecting.
  std::atomic<bool> stopLease_{false};
  // Counts up whenever its leases move (a piece traced, a cell loaded, a
  // file or photons received, a lease done); its heartbeats carry it, so
  // that the coordinator takes back the leases of a worker that stopped
  // moving (a read that never returns) while its heartbeats go on.
  std::atomic<uint64_t> progress_{0};
  int leasesStarted_ = 0;   // by the tracing thread (--crash-in-lease)
  bool stalled_ = false;    // a lease outlived --lease-limit-s: leaving with status 1
};

}  // namespace portico
