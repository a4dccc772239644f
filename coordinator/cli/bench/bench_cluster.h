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
  std::string csv;
};

int runBenchCluster(const BenchClusterOptions& options);

}  // namespace portico::cli
