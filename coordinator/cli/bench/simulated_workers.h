// One process of `portico bench coordinator`'s simulated workers: `count`
// workers, each its own DEALER socket and identity, speaking the protocol
// portico-worker speaks (Hello, Ready, Heartbeat, FetchPhotons, Result,
// Goodbye) to a real coordinator, and answering every lease at once with a
// Result of a traced one's shape (simulated_result.h). Run as the hidden
// `portico bench simulated-workers` by the bench, a few processes of ~64
// workers each.
//
// Each Result's send time and its latency to the worker's next Assign
// (FIFO: the leases in flight come back in the order their Results left)
// are written, with the process's totals, to the report file when SIGTERM
// (or SIGINT) ends it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "coordinator/cli/bench/simulated_result.h"

namespace portico::cli {

struct SimulatedWorkersOptions {
  std::string endpoint;
  uint32_t count = 64;
  uint32_t first = 0;   // the first worker's number (its name: sim-N)
  std::string report;   // where the totals and samples go
  ResultShape shape;
  bool depositRegions = true;   // write photon deposits into their regions (workers on the coordinator's file system)
};

int runSimulatedWorkers(const SimulatedWorkersOptions& options);

// A report as read back by the bench (every process's, merged).
struct SimulatedReport {
  SimulatedTally tally;
  int64_t bytesSent = 0, bytesReceived = 0, assigns = 0, photonFetches = 0, errors = 0;
  double cpuSeconds = 0;   // the processes' own (user + system)
  // The bytes of each phase's messages, both ways: Assigns and Results of
  // photon leases; of render leases, with FetchPhotons and their replies.
  int64_t phaseBytes[2] = {0, 0};
  // Per Result: when it left (steady clock, ns) and how long until that
  // worker's next Assign came (ns; -1: none came).
  std::vector<std::pair<int64_t, int64_t>> results;
  void add(const SimulatedReport& other);
};
// Throws std::runtime_error naming the file when it is missing or malformed.
SimulatedReport readSimulatedReport(const std::string& path);

}  // namespace portico::cli
