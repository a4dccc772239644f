#include "coordinator/cli/bench/coordinator_cost_table.h"

#include <gtest/gtest.h>

#include <fstream>
#include <stdexcept>
#include <string>

#include "common/util/temporary_directory.h"

namespace portico::cli {
namespace {

std::string write(const TemporaryDirectory& dir, const std::string& text) {
  const std::string path = (dir.path() / "coordinator.csv").string();
  std::ofstream(path) << text;
  return path;
}

TEST(CoordinatorCostTable, InterpolatesInLogWorkersAndHoldsTheEnds) {
  const TemporaryDirectory dir("portico-cost-table");
  // Columns as `bench coordinator --csv` writes them, others beside them, rows in any order.
  const std::string path = write(dir,
                                 "workers,leases,coordinator_cpu_ms_per_lease,bytes_per_work,balanced\n"
                                 "256,7000,0.4,48,1\n"
                                 "16,1400,1.0,40,1\n");
  const CoordinatorCostTable table(path);
  EXPECT_DOUBLE_EQ(table.at(1).cpuSecondsPerLease, 1.0e-3);     // below the first row: held
  EXPECT_DOUBLE_EQ(table.at(16).cpuSecondsPerLease, 1.0e-3);
  EXPECT_NEAR(table.at(64).cpuSecondsPerLease, 0.7e-3, 1e-12);  // half way from 16 to 256 in log
  EXPECT_NEAR(table.at(64).bytesPerWork[0], 44, 1e-9);   // no per-phase columns: bytes_per_work for both
  EXPECT_NEAR(table.at(64).bytesPerWork[1], 44, 1e-9);
  EXPECT_DOUBLE_EQ(table.at(1024).cpuSecondsPerLease, 0.4e-3);  // beyond the last: held
  EXPECT_DOUBLE_EQ(table.at(1024).bytesPerWork[0], 48);
}

TEST(CoordinatorCostTable, ReadsEachPhasesBytesWhereTheCsvHasThem) {
  const TemporaryDirectory dir("portico-cost-table");
  const CoordinatorCostTable table(write(dir,
                                         "workers,coordinator_cpu_ms_per_lease,bytes_per_work,bytes_per_photon_work,"
                                         "bytes_per_render_work\n"
                                         "64,0.5,40,9,300\n"));
  EXPECT_DOUBLE_EQ(table.at(64).bytesPerWork[0], 9);
  EXPECT_DOUBLE_EQ(table.at(64).bytesPerWork[1], 300);
}

TEST(CoordinatorCostTable, AFileWithoutTheColumnsOrWithABadRowIsRefusedNamingIt) {
  const TemporaryDirectory dir("portico-cost-table");
  try {
    CoordinatorCostTable table(write(dir, "workers,leases\n16,100\n"));
    FAIL() << "no cost columns accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("coordinator.csv:1: no column coordinator_cpu_ms_per_lease"),
              std::string::npos)
        << e.what();
  }
  try {
    CoordinatorCostTable table(write(dir, "workers,coordinator_cpu_ms_per_lease,bytes_per_work\n16,0.5,40\n64,x,40\n"));
    FAIL() << "a bad row accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("coordinator.csv:3:"), std::string::npos) << e.what();
  }
  EXPECT_THROW(CoordinatorCostTable(write(dir, "workers,coordinator_cpu_ms_per_lease,bytes_per_work\n")),
               std::invalid_argument);
}

}  // namespace
}  // namespace portico::cli
