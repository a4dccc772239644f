#include "coordinator/assign_encoder.h"

#include <gtest/gtest.h>

#include "common/net/message.h"
#include "coordinator/render_passes.h"

namespace portico {
namespace {

// A queued batch as jobs.db holds it: an emission range (packed) or rays (flat).
QueuedBatch emitBatch(uint32_t light, uint64_t firstPath, uint32_t count) {
  capnp::MallocMessageBuilder message;
  auto emit = message.initRoot<wire::RayBatch>().initEmit();
  emit.setLight(light);
  emit.setFirstPath(firstPath);
  emit.setCount(count);
  return {0, count, net::packToString(message), 0};
}
QueuedBatch rayBatch(uint32_t rays) {
  capnp::MallocMessageBuilder message;
  auto list = message.initRoot<wire::RayBatch>().initRays(rays);
  for (uint32_t i = 0; i < rays; ++i) list[i].setPathId(100 + i);
  return {0, rays, net::flatToString(message), 0};
}
QueuedBatch cameraBatch(uint32_t firstPixel, uint32_t pixels) {
  capnp::MallocMessageBuilder message;
  auto camera = message.initRoot<wire::RayBatch>().initCamera();
  camera.setFirstPixel(firstPixel);
  camera.setPixelCount(pixels);
  return {0, pixels, net::packToString(message), 0};
}

struct Spec {
  capnp::MallocMessageBuilder message;
  wire::JobSpec::Reader reader() { return message.getRoot<wire::JobSpec>().asReader(); }
  Spec() {
    auto spec = message.initRoot<wire::JobSpec>();
    spec.setStore("/stores/tower");
    spec.setSeed(7);
    spec.setSpp(4);
    spec.setPhotons(1000);
  }
};

TEST(AssignEncoder, APhotonLeaseCarriesItsBatchesMoreCellsRegionAndExpectation) {
  Spec spec;
  const std::vector<QueuedBatch> batches = {emitBatch(3, 0, 500), rayBatch(20)};
  const std::vector<std::pair<uint32_t, std::vector<QueuedBatch>>> moreCells = {{9, {rayBatch(5), rayBatch(7)}},
                                                                                {11, {emitBatch(1, 500, 30)}}};
  AssignContents contents;
  contents.lease = {42, 3, 17, 0, "w", 2};
  contents.spec = spec.reader();
  contents.photonJob = 3;
  contents.cellWork = 400;   // less than the lease holds: cellWork says at least the lease's
  contents.region = AssignContents::Region{"/db/jobs.db-photons/job-3.bin", 8192, 65536};
  contents.batches = &batches;
  contents.moreCells = &moreCells;
  EXPECT_EQ(leaseWorkOf(contents), 500 + 20 + 5 + 7 + 30);

  capnp::MallocMessageBuilder message;
  const LeaseExpectation expected = encodeAssign(contents, message);
  EXPECT_EQ(expected.phase, 0);
  EXPECT_EQ(expected.photonsToEmit, 530);
  EXPECT_EQ(expected.raysIn, 32);
  EXPECT_EQ(expected.cameraSamples, 0);

  // As the worker reads it: through the wire encoding.
  net::Decoded decoded(net::encode(message, net::Encoding::Flat));
  const auto assign = decoded.envelope().getAssign();
  EXPECT_EQ(assign.getLease(), 42u);
  EXPECT_EQ(assign.getAttempt(), 2u);
  EXPECT_EQ(assign.getJob(), 3u);
  EXPECT_EQ(assign.getCell(), 17u);
  EXPECT_EQ(assign.getPhase(), wire::Phase::PHOTONS);
  EXPECT_EQ(assign.getPhotonJob(), 3u);
  EXPECT_EQ(assign.getLeaseWork(), 562);
  EXPECT_EQ(assign.getCellWork(), 562);
  EXPECT_EQ(assign.getSpec().getSeed(), 7u);   // a photon lease: the job's own seed
  EXPECT_EQ(std::string(assign.getSpec().getStore().cStr()), "/stores/tower");
  ASSERT_TRUE(assign.hasDepositRegion());
  EXPECT_EQ(std::string(assign.getDepositRegion().getPath().cStr()), "/db/jobs.db-photons/job-3.bin");
  EXPECT_EQ(assign.getDepositRegion().getOffset(), 8192u);
  EXPECT_EQ(assign.getDepositRegion().getSize(), 65536u);
  ASSERT_EQ(assign.getBatches().size(), 2u);
  EXPECT_EQ(assign.getBatches()[0].getEmit().getCount(), 500u);
  ASSERT_EQ(assign.getBatches()[1].getRays().size(), 20u);
  EXPECT_EQ(assign.getBatches()[1].getRays()[19].getPathId(), 119u);
  ASSERT_EQ(assign.getMoreCells().size(), 2u);
  EXPECT_EQ(assign.getMoreCells()[0].getCell(), 9u);
  EXPECT_EQ(assign.getMoreCells()[0].getBatches().size(), 2u);
  EXPECT_EQ(assign.getMoreCells()[1].getCell(), 11u);
  EXPECT_EQ(assign.getMoreCells()[1].getBatches()[0].getEmit().getFirstPath(), 500u);
}

TEST(AssignEncoder, ARenderLeaseCarriesItsPassSeedAndCountsCameraSamples) {
  Spec spec;
  const std::vector<QueuedBatch> batches = {cameraBatch(0, 64), rayBatch(3)};
  AssignContents contents;
  contents.lease = {5, 2, 1, 1, "w", 1};
  contents.spec = spec.reader();
  contents.photonJob = 1;
  contents.renderPass = 2;
  contents.cellWork = 1000;
  contents.batches = &batches;
  capnp::MallocMessageBuilder message;
  const LeaseExpectation expected = encodeAssign(contents, message);
  EXPECT_EQ(expected.phase, 1);
  EXPECT_EQ(expected.cameraSamples, 64 * 4);
  EXPECT_EQ(expected.raysIn, 3);
  const auto assign = message.getRoot<wire::Envelope>().asReader().getAssign();
  EXPECT_EQ(assign.getPhase(), wire::Phase::RENDER);
  EXPECT_EQ(assign.getSpec().getSeed(), passSeed(7, 2));
  EXPECT_EQ(assign.getCellWork(), 1000);
  EXPECT_FALSE(assign.hasDepositRegion());
  EXPECT_EQ(assign.getMoreCells().size(), 0u);
}

}  // namespace
}  // namespace portico
