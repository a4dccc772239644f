// `portico bench coordinator`: the real portico-coordinator, on its real
// ZeroMQ socket (ipc:// in a private folder, as `portico render` runs it),
// driven by N simulated workers (simulated_workers.h) through a job on a
// generated building, for several N. Measures the sustained leases per
// second, the coordinator's CPU per lease, Result-to-next-Assign latency and
// the bytes through the coordinator, and checks that the job's accounting
// balanced (docs/coordinator-benchmark.md).
#pragma once

#include <cstdint>
#include <string>

#include "coordinator/cli/bench/simulated_result.h"

namespace portico::cli {

struct BenchCoordinatorOptions {
  std::string workers = "16,64,256,1024";   // simulated worker counts, one run each
  std::string preset = "tower";
  uint32_t floors = 10;
  uint64_t sceneSeed = 1;
  std::string store;                 // reused when it holds a store, else generated there and kept
  uint64_t photonsPerLight = 1000;   // the job's photons: this many per light of the building
  int64_t leaseRays = 1000;          // the coordinator's --lease-rays: leases of ~1 ms of a 1 M rays/s worker
  uint32_t width = 320, height = 180;
  uint32_t workersPerProcess = 64;
  bool depositRegions = true;        // simulated workers write deposits into their regions (shared file system)
  ResultShape shape;
  double timeoutSeconds = 900;       // per run
  bool quick = false;                // 2 floors, 200 photons per light, --workers 4,16 unless given
  bool keep = false;                 // keep each run's folder (jobs.db, logs)
  std::string csv, plot;
};

int runBenchCoordinator(BenchCoordinatorOptions options, bool workersGiven, bool floorsGiven, bool photonsGiven);

}  // namespace portico::cli
