// The cluster model against a measured run: `portico bench cluster` replays
// a finished job's lease log for its own worker count and predicts its
// time (docs/large-buildings.md, "Cluster model").
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <sstream>
#include <string>

#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;

class ClusterModelRun : public DemoStoreSuite<ClusterModelRun> {};

// The CSV's rows: record,workers,measured_s,predicted_s,...
std::vector<std::vector<std::string>> csvRows(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream lines(text);
  std::string line;
  std::getline(lines, line);   // header
  while (std::getline(lines, line)) {
    std::vector<std::string> fields;
    std::istringstream cells(line);
    std::string field;
    while (std::getline(cells, field, ',')) fields.push_back(field);
    rows.push_back(fields);
  }
  return rows;
}

TEST_F(ClusterModelRun, TheModelReproducesAMeasuredOneWorkerRun) {
  const fs::path dir = dir_ / "one-worker";
  {
    LocalCluster cluster(dir, 1);
    const uint64_t job = cluster.submit(store_, dir / "image.exr", 300000, 2);
    const auto status = cluster.wait(job);
    ASSERT_EQ(status.value("state", ""), "done") << status.dump(2);
  }
  // Its own run replayed on the cores its job had (others' work beside it
  // included), then 1 and 4 workers on a machine each.
  const fs::path csv = dir / "model.csv", cluster = dir / "cluster.csv";
  ASSERT_EQ(runCommand({kBin + "portico", "bench", "cluster", (dir / "jobs.db").string(), "--workers", "1",
                        "--host-cores", "measured", "--csv", csv.string()},
                       dir / "bench.log"),
            0)
      << readFile(dir / "bench.log");
  ASSERT_EQ(runCommand({kBin + "portico", "bench", "cluster", (dir / "jobs.db").string(), "--workers", "1,4",
                        "--csv", cluster.string()},
                       dir / "bench.log"),
            0)
      << readFile(dir / "bench.log");
  const auto rows = csvRows(readFile(csv));
  ASSERT_EQ(rows.size(), 2u) << readFile(csv);
  ASSERT_GE(rows[0].size(), 4u);
  EXPECT_EQ(rows[0][1], "1");
  const double measured = std::stod(rows[0][2]), predicted = std::stod(rows[0][3]);
  std::cout << "measured " << measured << " s, predicted " << predicted << " s\n";
  // Generous: a shared 2-core machine whose load changes during the run.
  EXPECT_GT(measured, 0.0);
  EXPECT_NEAR(predicted, measured, 0.35 * measured) << readFile(csv);
  // Four workers share the same work: faster, never more than 4x.
  const auto machines = csvRows(readFile(cluster));
  ASSERT_EQ(machines.size(), 3u) << readFile(cluster);
  const double one = std::stod(machines[1][3]), four = std::stod(machines[2][3]);
  EXPECT_LT(four, one);
  EXPECT_GT(four, one / 4.5);
}

// The model on the machine the runs shared (--host-cores measured: the
// cores each predicted run's job had, its CPU over its time, whatever else
// ran beside it): a 1-worker run's record predicts the 2-worker run.
TEST_F(ClusterModelRun, AOneWorkerRecordPredictsTheTwoWorkerRunOnTheSameCores) {
  std::vector<fs::path> records;
  for (size_t workers : {1, 2}) {
    const fs::path dir = dir_ / fmt::format("workers-{}", workers);
    LocalCluster cluster(dir, workers);
    const uint64_t job = cluster.submit(store_, dir / "image.exr", 300000, 2);
    const auto status = cluster.wait(job);
    ASSERT_EQ(status.value("state", ""), "done") << status.dump(2);
    records.push_back(dir / "jobs.db");
  }
  const fs::path csv = dir_ / "model.csv";
  ASSERT_EQ(runCommand({kBin + "portico", "bench", "cluster", records[0].string(), records[1].string(), "--workers",
                        "2", "--host-cores", "measured", "--csv", csv.string()},
                       dir_ / "bench.log"),
            0)
      << readFile(dir_ / "bench.log");
  const auto rows = csvRows(readFile(csv));
  // The 1-worker record at 1 worker and at 2, the 2-worker record at 2 and 1, then --workers.
  ASSERT_EQ(rows.size(), 5u) << readFile(csv);
  ASSERT_EQ(rows[1][1], "2");
  const double measured = std::stod(rows[1][2]), predicted = std::stod(rows[1][3]);
  std::cout << "2 workers: measured " << measured << " s, predicted from 1 worker " << predicted << " s\n";
  // 50 %: on this 3 s job the 2-worker run's workers spend 40-60 % more
  // CPU in their leases than the 1-worker run's: both build the photon
  // maps and irradiance of the few cells they render, second copies the
  // model does not count (it counts second loads of a cell's triangles);
  // and the runs meet different loads beside them (the cores each had is
  // measured, not when). Measured under load: -29 % to -39 %; the 2-floor
  // tower's runs are within 15 % but where other work slowed a run
  // (docs/large-buildings.md).
  EXPECT_NEAR(predicted, measured, 0.5 * measured) << readFile(csv) << readFile(dir_ / "bench.log");
}

}  // namespace
}  // namespace portico
