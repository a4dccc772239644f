// `portico bench cluster`: the cluster model (coordinator/cluster_model.h)
// on finished jobs' records: each record replayed at its own worker count
// against what it measured, then the first at --workers counts.
#pragma once

#include <string>
#include <vector>

namespace portico::cli {

struct BenchClusterOptions {
  // JOBS_DB or JOBS_DB:JOB (default: its newest done job), one per measured run.
  std::vector<std::string> records;
  std::string workers = "1,2,16,64,256";
  std::string memory = "1GiB";     // each modelled worker's --memory
  double latencyMicros = 100;      // one way, coordinator to worker
  // "0": a machine per worker; C: all of them share C cores
  // (ClusterModelOptions::hostCores); "measured": as many as the job's own
  // threads had in the run predicted (its CPU over its time).
  std::string hostCores = "0";
  double workScale = 1;            // the records' tracing work times this
  double leaseScale = 1;           // each lease's work times this (ClusterModelOptions::leaseScale)
  // The coordinator's CPU per lease and the bytes per unit of a lease's
  // work through it, at each worker count, from `portico bench
  // coordinator`'s CSV ("": each record's CPU, no bytes charged); the
  // scalars override it (< 0 / 0: not given). Bytes go on a link of linkGbit.
  std::string coordinatorBench;
  double coordinatorMsPerLease = -1;
  double bytesPerRay = 0;
  double linkGbit = 10;
  std::string csv;
};

int runBenchCluster(const BenchClusterOptions& options);

}  // namespace portico::cli
