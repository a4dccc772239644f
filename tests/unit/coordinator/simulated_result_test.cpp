// `portico bench coordinator`'s simulated Results must pass the checks the
// coordinator applies to every Result (coordinator/result_check.h): else
// the bench measures refusals, not leases.
#include "coordinator/cli/bench/simulated_result.h"

#include <gtest/gtest.h>

#include "common/net/message.h"
#include "coordinator/result_check.h"

namespace portico::cli {
namespace {

// Three cells in a row: 0 - 1 - 2.
constexpr size_t kCells = 3;
CellNeighbours neighbours() {
  std::vector<Portal> portals(2);
  portals[0].cellA = 0, portals[0].cellB = 1;
  portals[1].id = 1, portals[1].cellA = 1, portals[1].cellB = 2;
  return CellNeighbours(kCells, portals);
}

// A lease's header and room for its two batches.
capnp::List<wire::RayBatch>::Builder leaseOf(wire::Assign::Builder assign, uint64_t lease, wire::Phase phase,
                                              uint32_t cell, uint32_t spp) {
  assign.setLease(lease);
  assign.setPhase(phase);
  assign.setCell(cell);
  assign.initSpec().setSpp(spp);
  return assign.initBatches(2);
}

// A photon lease: an emission batch, received rays (some already deep), and a more cell.
void photonLease(wire::Assign::Builder assign) {
  auto batches = leaseOf(assign, 7, wire::Phase::PHOTONS, 0, 1);
  auto emit = batches[0].initEmit();
  emit.setLight(0), emit.setFirstPath(1000), emit.setCount(3000), emit.setPhotonsOfLight(100000);
  auto rays = batches[1].initRays(500);
  for (unsigned i = 0; i < rays.size(); ++i) rays[i].setDepth(uint16_t(i % 10)), rays[i].setPathId(i);
  auto more = assign.initMoreCells(1);
  more[0].setCell(1);
  auto moreEmit = more[0].initBatches(1)[0].initEmit();
  moreEmit.setCount(777), moreEmit.setFirstPath(5);
  assign.setLeaseWork(3000 + 500 + 777);
}

LeaseExpectation expectationOf(wire::Assign::Reader assign) {
  LeaseExpectation expected;
  expected.phase = assign.getPhase() == wire::Phase::PHOTONS ? 0 : 1;
  const uint32_t spp = assign.getSpec().getSpp();
  for (auto batch : assign.getBatches()) expected.add(batch, spp);
  for (auto more : assign.getMoreCells())
    for (auto batch : more.getBatches()) expected.add(batch, spp);
  return expected;
}

TEST(SimulatedResult, APhotonLeasesResultAddsUpAndHasATracedOnesShape) {
  capnp::MallocMessageBuilder message;
  photonLease(message.initRoot<wire::Assign>());
  const auto assign = message.getRoot<wire::Assign>().asReader();
  const ResultShape shape;
  const SimulatedResult out = simulateResult(assign, shape, neighbours(), false);
  const auto result = out.message->getRoot<wire::Envelope>().asReader().getResult();
  const LeaseExpectation expected = expectationOf(assign);
  EXPECT_NO_THROW(checkResultCounts(&expected, 0, result));
  EXPECT_EQ(out.tally.emitted, 3000 + 777);
  // 3.13 records per photon started, 0.13 handed on (the deep rays end where they are).
  EXPECT_NEAR(double(out.tally.depositRecords), 3.13 * (3000 + 500 + 777), 2);
  EXPECT_GT(out.tally.photonsHandedOn, int64_t(0.12 * (3000 + 777)));
  EXPECT_LT(out.tally.photonsHandedOn, int64_t(0.14 * (3000 + 500 + 777)));
  for (auto crossing : result.getCrossings()) {
    EXPECT_LT(crossing.getCell(), kCells);
    for (auto ray : crossing.getRays()) EXPECT_LT(ray.getDepth(), shape.maxDepth);
  }
  // Miscounted (the bench test's fault): refused.
  ResultShape miscount = shape;
  miscount.miscount = true;
  const SimulatedResult bad = simulateResult(assign, miscount, neighbours(), false);
  EXPECT_THROW(checkResultCounts(&expected, 0, bad.message->getRoot<wire::Envelope>().asReader().getResult()),
               BadResultError);
}

TEST(SimulatedResult, ARenderLeasesResultAddsUpWithItsFilmInRange) {
  capnp::MallocMessageBuilder message;
  auto batches = leaseOf(message.initRoot<wire::Assign>(), 9, wire::Phase::RENDER, 1, 4);
  auto camera = batches[0].initCamera();
  camera.setFirstPixel(100), camera.setPixelCount(256);
  batches[1].initRays(40);
  const auto reader = message.getRoot<wire::Assign>().asReader();
  const SimulatedResult out = simulateResult(reader, ResultShape{}, neighbours(), false);
  const auto result = out.message->getRoot<wire::Envelope>().asReader().getResult();
  const LeaseExpectation expected = expectationOf(reader);
  EXPECT_NO_THROW(checkResultCounts(&expected, 1, result));
  EXPECT_EQ(out.tally.cameraRays, 256 * 4);
  ASSERT_EQ(result.getFilm().size(), 256u);
  for (auto pixel : result.getFilm()) EXPECT_NO_THROW(checkFilmValue(pixel, 100000));
  EXPECT_EQ(result.getDeposits().size(), 0u);
}

}  // namespace
}  // namespace portico::cli
