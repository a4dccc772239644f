// The worker's conversation with the coordinator (a DEALER socket): Hello,
// heartbeats both ways, leases in, results out, reconnect when the
// coordinator goes silent. Tracing runs on a second thread so heartbeats
// keep flowing during a long lease.
#pragma once

#include <capnp/message.h>

#include <atomic>
#include <cstdint>
#include <future>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/net/curve_keys.h"
#include "proto/wire.capnp.h"

#include "worker/accelerator_choice.h"
#include "worker/cell_cache.h"
#include "worker/store_mirror.h"

namespace portico {

struct WorkerOptions {
  std::string connect = "tcp://127.0.0.1:5555";
  std::string name;
  uint64_t memoryBytes = uint64_t(2) << 30;
  uint32_t threads = 1;
  int heartbeatMs = 1000;
  int livenessMs = 10000;      // coordinator silence before reconnecting
  // Fault injection for recovery tests: exit abruptly, without reporting it,
  // when the Nth lease is finished (0: never).
  int crashAfterLeases = 0;
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
};

class WorkerSession {
 public:
  explicit WorkerSession(WorkerOptions options);
  ~WorkerSession();
  // Serves until stop(), a Shutdown message, or a refused Hello. Returns the exit code.
  int run();
  void stop() { stopping_ = true; }

 private:
  // Traces the lease on its own thread and signals leaseDone_ when finished.
  std::future<std::unique_ptr<capnp::MallocMessageBuilder>> startLease(
      wire::Assign::Reader assign, std::optional<std::vector<StoredPhoton>> photons);

  WorkerOptions options_;
  std::unique_ptr<StoreMirror> mirror_;
  std::optional<net::ClientKeys> keys_;
  CellCache cache_;
  AcceleratorChooser chooser_;
  int leaseDone_;   // eventfd
  std::atomic<bool> stopping_{false};
};

}  // namespace portico
