// One lease of several cells (Assign.moreCells, the end of a photon pass)
// against the real worker code on a generated store: the same photons as a
// lease per cell, and a bad cell among the more cells blamed by name.
#include <capnp/message.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "common/scene/store/scene_store.h"
#include "common/transport/photon_record.h"
#include "tests/integration/service_harness.h"
#include "worker/lease_load.h"
#include "worker/lease_runner.h"

namespace portico {
namespace {

using namespace harness;

struct Emission {
  uint32_t light, cell;
};

// A photon-pass Assign: `count` photons of each emission's light, the first
// emission's cell as the lease's own, the others as more cells.
void fillAssign(wire::Assign::Builder assign, const std::string& store, const std::vector<Emission>& emissions,
                uint32_t count) {
  assign.setLease(1);
  assign.setAttempt(1);
  assign.setJob(1);
  assign.setPhase(wire::Phase::PHOTONS);
  auto spec = assign.initSpec();
  spec.setStore(store);
  // The job's photons, the same for every lease of it whatever it holds
  // (records store power against the job's mean per photon).
  spec.setPhotons(uint64_t(count) * 16);
  spec.setSpp(1);
  spec.setSeed(7);
  spec.setAccel("grid");
  spec.setWidth(8);
  spec.setHeight(8);
  spec.setLightSamples(1);
  spec.setPhotonK(16);
  spec.setPhotonRadius(0.5f);
  const auto fillEmit = [&](wire::RayBatch::Builder batch, const Emission& e) {
    auto emit = batch.initEmit();
    emit.setLight(e.light);
    emit.setFirstPath(uint64_t(e.light) << 32);
    emit.setCount(count);
    emit.setPhotonsOfLight(count);
  };
  assign.setCell(emissions.front().cell);
  fillEmit(assign.initBatches(1)[0], emissions.front());
  auto more = assign.initMoreCells(unsigned(emissions.size() - 1));
  for (size_t i = 1; i < emissions.size(); ++i) {
    more[unsigned(i - 1)].setCell(emissions[i].cell);
    fillEmit(more[unsigned(i - 1)].initBatches(1)[0], emissions[i]);
  }
  assign.setLeaseWork(int64_t(count * emissions.size()));
  assign.setCellWork(int64_t(count));
}

// The Result's photon records per cell, sorted (a table's order is not its content).
std::map<uint32_t, std::multiset<std::string>> depositsOf(capnp::MallocMessageBuilder& message) {
  std::map<uint32_t, std::multiset<std::string>> deposits;
  for (auto cell : message.getRoot<wire::Envelope>().getResult().getDeposits()) {
    auto bytes = cell.getRecords();
    EXPECT_EQ(bytes.size() % sizeof(PhotonRecord), 0u);
    for (size_t at = 0; at + sizeof(PhotonRecord) <= bytes.size(); at += sizeof(PhotonRecord))
      deposits[cell.getCell()].insert(
          std::string(reinterpret_cast<const char*>(bytes.begin() + at), sizeof(PhotonRecord)));
  }
  return deposits;
}

class LeaseRunner : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = makeTempDirectory("lease-runner");
    store_ = dir_ / "demo";
    ASSERT_EQ(generateDemoStore(store_, 3), "");
    const SceneStore scene = SceneStore::open(store_.string());
    std::set<uint32_t> cells;
    for (uint32_t light = 0; light < scene.lights().size(); ++light)
      if (cells.insert(scene.lights()[light].cell).second) emissions_.push_back({light, scene.lights()[light].cell});
  }
  static fs::path dir_, store_;
  static std::vector<Emission> emissions_;   // one light in each of the lit cells
};
fs::path LeaseRunner::dir_, LeaseRunner::store_;
std::vector<Emission> LeaseRunner::emissions_;

TEST_F(LeaseRunner, OneLeaseOfSeveralCellsDepositsWhatALeasePerCellDoes) {
  ASSERT_GE(emissions_.size(), 3u) << "the demo building lights at least three rooms";
  const std::vector<Emission> used(emissions_.begin(), emissions_.begin() + 3);
  AcceleratorChooser chooser(CostModel::builtIn());

  CellCache together(uint64_t(1) << 30);
  capnp::MallocMessageBuilder assignAll;
  fillAssign(assignAll.initRoot<wire::Assign>(), store_.string(), used, 2000);
  auto all = runLease(together, chooser, assignAll.getRoot<wire::Assign>().asReader(), std::nullopt, store_.string(), 0);
  const auto combined = depositsOf(*all);

  std::map<uint32_t, std::multiset<std::string>> separate;
  for (const Emission& e : used) {
    CellCache alone(uint64_t(1) << 30);
    capnp::MallocMessageBuilder assignOne;
    fillAssign(assignOne.initRoot<wire::Assign>(), store_.string(), {e}, 2000);
    auto one = runLease(alone, chooser, assignOne.getRoot<wire::Assign>().asReader(), std::nullopt, store_.string(), 0);
    for (auto& [cell, records] : depositsOf(*one)) separate[cell].insert(records.begin(), records.end());
  }
  size_t records = 0;
  for (const auto& [cell, set] : combined) records += set.size();
  EXPECT_GT(records, 3000u);
  EXPECT_EQ(combined, separate);
  size_t extraCells = 0;
  for (auto counter : all->getRoot<wire::Envelope>().getResult().getCounters())
    if (std::string(counter.getName().cStr()) == "leases.extra_cells") extraCells = size_t(counter.getValue());
  EXPECT_EQ(extraCells, 2u);
}

// `--accel auto`: a more cell comes with a piece of its emission; it is
// chosen for every light's photons of its cell (each at the piece's light's
// share), not for the piece.
TEST_F(LeaseRunner, AutoChoosesAnEmittingMoreCellForEveryLightOfIt) {
  ASSERT_GE(emissions_.size(), 3u);
  const std::vector<Emission> used(emissions_.begin(), emissions_.begin() + 3);
  capnp::MallocMessageBuilder message;
  auto assign = message.initRoot<wire::Assign>();
  fillAssign(assign, store_.string(), used, 500);
  assign.getSpec().setAccel("auto");
  CellCache cache(uint64_t(1) << 30);
  AcceleratorChooser chooser(CostModel::builtIn());
  const LoadedLease lease = loadLease(cache, chooser, assign.asReader(), std::nullopt, store_.string());
  const SceneStore scene = SceneStore::open(store_.string());
  ASSERT_EQ(lease.morePendingWork.size(), used.size() - 1);
  for (size_t i = 1; i < used.size(); ++i) {
    int64_t lights = 0;
    for (const AreaLight& light : scene.lights()) lights += light.cell == used[i].cell;
    EXPECT_EQ(lease.morePendingWork[i - 1].first, used[i].cell);
    EXPECT_EQ(lease.morePendingWork[i - 1].second, 500 * lights);
  }

  assign.getSpec().setAccel("grid");   // a fixed structure needs no estimate
  EXPECT_TRUE(loadLease(cache, chooser, assign.asReader(), std::nullopt, store_.string()).morePendingWork.empty());
}

TEST_F(LeaseRunner, ABadCellAmongTheMoreCellsIsTheOneBlamed) {
  ASSERT_GE(emissions_.size(), 2u);
  const fs::path store = dir_ / "corrupt";
  fs::copy(store_, store, fs::copy_options::recursive);
  const SceneStore scene = SceneStore::open(store.string());
  const Emission bad = emissions_[1];
  {
    std::ofstream cell(store / scene.cells()[bad.cell].file, std::ios::binary | std::ios::trunc);
    std::mt19937 random(1);
    for (int i = 0; i < 4096; ++i) cell.put(static_cast<char>(random()));
  }
  CellCache cache(uint64_t(1) << 30);
  AcceleratorChooser chooser(CostModel::builtIn());
  capnp::MallocMessageBuilder assign;
  fillAssign(assign.initRoot<wire::Assign>(), store.string(), {emissions_[0], bad}, 500);
  try {
    runLease(cache, chooser, assign.getRoot<wire::Assign>().asReader(), std::nullopt, store.string(), 0);
    ADD_FAILURE() << "a lease with a corrupt cell succeeded";
  } catch (const MoreCellError& e) {
    EXPECT_EQ(e.cell, bad.cell);
    EXPECT_NE(std::string(e.what()).find(scene.cells()[bad.cell].file), std::string::npos) << e.what();
  }
}

// Photon records store positions on a lattice over their table's cell
// (PhotonFrame: the cell's bounds grown by the photon radius), clamping
// what lies outside. Nothing a lease deposits may need the clamp: not the
// photons in rooms, not their copies across portals, not those in voxel
// cells whose triangles stick out of the voxel.
TEST_F(LeaseRunner, EveryDepositLiesInsideItsTablesLattice) {
  const fs::path voxels = dir_ / "two_rooms_grid3";
  ASSERT_EQ(importVoxelStore("two_rooms", 3, voxels), "");
  for (const fs::path& store : {store_, voxels}) {
    const SceneStore scene = SceneStore::open(store.string());
    AcceleratorChooser chooser(CostModel::builtIn());
    CellCache cache(uint64_t(1) << 30);
    size_t records = 0, copies = 0;
    for (uint32_t light = 0; light < scene.lights().size(); ++light) {
      capnp::MallocMessageBuilder assign;
      fillAssign(assign.initRoot<wire::Assign>(), store.string(), {{light, scene.lights()[light].cell}}, 20000);
      // Crossings into cells an earlier lease loaded are traced here too.
      auto result = runLease(cache, chooser, assign.getRoot<wire::Assign>().asReader(), std::nullopt, store.string(),
                             1000000);
      for (auto table : result->getRoot<wire::Envelope>().getResult().getDeposits()) {
        const uint32_t cell = table.getCell();
        ASSERT_LT(cell, scene.cells().size());
        auto bytes = table.getRecords();
        ASSERT_EQ(bytes.size() % sizeof(PhotonRecord), 0u);
        for (size_t at = 0; at < bytes.size(); at += sizeof(PhotonRecord)) {
          PhotonRecord r;
          std::memcpy(&r, bytes.begin() + at, sizeof r);
          for (uint32_t axis = 0; axis < 3; ++axis) {
            const uint64_t step = (r.bits >> (PhotonFrame::kBits * axis)) & PhotonFrame::kLastStep;
            ASSERT_GT(step, 0u) << store << " cell " << cell << " axis " << axis;
            ASSERT_LT(step, PhotonFrame::kLastStep) << store << " cell " << cell << " axis " << axis;
          }
          ++records;
          copies += cell != scene.lights()[light].cell;
        }
      }
    }
    EXPECT_GT(records, 500u) << store;
    EXPECT_GT(copies, 0u) << store << ": no copy across a portal was checked";
  }
}

}  // namespace
}  // namespace portico
