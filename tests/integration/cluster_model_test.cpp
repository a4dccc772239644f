// The cluster model against a measured run: `portico bench cluster` replays
// a finished job's lease log for its own worker count and predicts its
// time (docs/large-buildings.md, "Cluster model").
#include <gtest/gtest.h>

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
  const fs::path csv = dir / "model.csv";
  ASSERT_EQ(runCommand({kBin + "portico", "bench", "cluster", (dir / "jobs.db").string(), "--workers", "1,4",
                        "--csv", csv.string()},
                       dir / "bench.log"),
            0)
      << readFile(dir / "bench.log");
  const auto rows = csvRows(readFile(csv));
  ASSERT_EQ(rows.size(), 3u) << readFile(csv);   // its own run, then 1 and 4 workers predicted
  ASSERT_GE(rows[0].size(), 4u);
  EXPECT_EQ(rows[0][1], "1");
  const double measured = std::stod(rows[0][2]), predicted = std::stod(rows[0][3]);
  std::cout << "measured " << measured << " s, predicted " << predicted << " s\n";
  // Generous: a shared 2-core machine, and the model leaves out the
  // coordinator's gaps between phases.
  EXPECT_GT(measured, 0.0);
  EXPECT_NEAR(predicted, measured, 0.35 * measured) << readFile(csv);
  // Four workers share the same work: faster, never more than 4x.
  const double four = std::stod(rows[2][3]);
  EXPECT_LT(four, predicted);
  EXPECT_GT(four, predicted / 4.5);
}

}  // namespace
}  // namespace portico
