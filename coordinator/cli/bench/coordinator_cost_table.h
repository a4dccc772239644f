// What `portico bench coordinator` measured the coordinator to cost, read
// back from its CSV for the cluster model (`portico bench cluster
// --coordinator-bench FILE`): its CPU per lease and the bytes through it per
// unit of lease work, at each simulated worker count, interpolated between
// them in log(workers) and held at the ends.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace portico::cli {

struct CoordinatorCost {
  double cpuSecondsPerLease = 0;
  double bytesPerWork[2] = {0, 0};   // photon pass, render (a CSV without them: bytes_per_work for both)
};

class CoordinatorCostTable {
 public:
  // Throws std::invalid_argument naming the file (and line) when it cannot
  // be read, lacks the columns, or has no row.
  explicit CoordinatorCostTable(const std::string& csvPath);
  CoordinatorCost at(size_t workers) const;

 private:
  struct Row {
    double workers;
    CoordinatorCost cost;
  };
  std::vector<Row> rows_;   // by workers
};

}  // namespace portico::cli
