#include "coordinator/assign_encoder.h"

#include <algorithm>

#include "common/net/message.h"
#include "coordinator/render_passes.h"

namespace portico {

int64_t leaseWorkOf(const AssignContents& contents) {
  int64_t work = 0;
  for (const QueuedBatch& batch : *contents.batches) work += batch.work;
  if (contents.moreCells)
    for (const auto& [cell, batches] : *contents.moreCells)
      for (const QueuedBatch& batch : batches) work += batch.work;
  return work;
}

LeaseExpectation encodeAssign(const AssignContents& contents, capnp::MallocMessageBuilder& message) {
  const LeaseRecord& lease = contents.lease;
  const int64_t leaseWork = leaseWorkOf(contents);
  auto assign = message.initRoot<wire::Envelope>().initAssign();
  assign.setLease(lease.id);
  assign.setAttempt(lease.attempt);
  assign.setJob(lease.job);
  assign.setPhase(lease.phase == 0 ? wire::Phase::PHOTONS : wire::Phase::RENDER);
  assign.setCell(lease.cell);
  assign.setSpec(contents.spec);
  assign.setPhotonJob(contents.photonJob);
  if (lease.phase == 1) assign.getSpec().setSeed(passSeed(contents.spec.getSeed(), contents.renderPass));
  assign.setLeaseWork(leaseWork);
  assign.setCellWork(std::max(contents.cellWork, leaseWork));
  LeaseExpectation expected;
  expected.phase = lease.phase;
  const uint32_t spp = contents.spec.getSpp();
  const auto copyBatches = [&](const std::vector<QueuedBatch>& from, capnp::List<wire::RayBatch>::Builder to) {
    for (size_t i = 0; i < from.size(); ++i) {
      net::MessageReader reader(from[i].payload.data(), from[i].payload.size());   // packed or flat
      const auto batch = reader.root<wire::RayBatch>();
      expected.add(batch, spp);
      to.setWithCaveats(static_cast<unsigned>(i), batch);
    }
  };
  if (contents.region) {
    auto target = assign.initDepositRegion();
    target.setPath(contents.region->path);
    target.setOffset(uint64_t(contents.region->offset));
    target.setSize(uint64_t(contents.region->size));
  }
  copyBatches(*contents.batches, assign.initBatches(static_cast<unsigned>(contents.batches->size())));
  if (contents.moreCells && !contents.moreCells->empty()) {
    auto more = assign.initMoreCells(static_cast<unsigned>(contents.moreCells->size()));
    for (size_t i = 0; i < contents.moreCells->size(); ++i) {
      const auto& [cell, batches] = (*contents.moreCells)[i];
      more[unsigned(i)].setCell(cell);
      copyBatches(batches, more[unsigned(i)].initBatches(static_cast<unsigned>(batches.size())));
    }
  }
  return expected;
}

}  // namespace portico
