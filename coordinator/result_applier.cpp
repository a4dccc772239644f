#include "coordinator/result_applier.h"

#include <capnp/message.h>
#include <fmt/format.h>

#include <unordered_map>

#include "common/net/message.h"
#include "common/transport/film.h"
#include "common/transport/photon_record.h"
#include "coordinator/job_report.h"
#include "coordinator/result_check.h"

namespace portico {

void applyResult(JobStore& store, const ResultTarget& target, const DepositRegionGrant* region,
                 wire::Result::Reader result) {
  for (auto crossing : result.getCrossings()) {
    if (crossing.getCell() >= target.cellCount)
      throw BadResultError(fmt::format("it sends rays to cell {}, which does not exist", crossing.getCell()));
    // One first segment that holds the whole copy: no growth, no second segment.
    capnp::MallocMessageBuilder batch(uint(crossing.getRays().totalSize().wordCount + 8));
    batch.initRoot<wire::RayBatch>().setRays(crossing.getRays());
    store.addBatch(target.job, crossing.getCell(), target.phase, BatchKind::Rays, crossing.getRays().size(),
                   net::flatToString(batch));   // rays: packing gains little, costs a pass each way
  }
  int64_t regionBytes = 0, resultBytes = 0;
  std::vector<RegionDeposit> inRegion;
  try {
    inRegion = regionDeposits(target.lease, region, result, target.cellCount);
  } catch (const std::runtime_error& e) {
    throw BadResultError(e.what());
  }
  for (const RegionDeposit& d : inRegion) {
    store.addPhotonsAt(target.job, d.cell, d.extent);
    regionBytes += d.extent.size;
  }
  for (auto deposits : result.getDeposits()) {
    if (deposits.getCell() >= target.cellCount)
      throw BadResultError(fmt::format("it deposits photons in cell {}, which does not exist", deposits.getCell()));
    auto records = deposits.getRecords();
    if (records.size() == 0) continue;
    if (records.size() % sizeof(PhotonRecord) != 0)
      throw BadResultError(fmt::format("it holds a photon table of {} bytes, not whole records", records.size()));
    store.addPhotons(target.job, deposits.getCell(), records.size() / sizeof(PhotonRecord),
                     std::string_view(reinterpret_cast<const char*>(records.begin()), records.size()));
    resultBytes += int64_t(records.size());
  }
  if (regionBytes > 0) store.addCounter(target.job, kPhotonBytesFromWorkersCounter, regionBytes);
  if (resultBytes > 0) store.addCounter(target.job, kPhotonBytesFromResultsCounter, resultBytes);
  if (result.getFilm().size() > 0) {
    std::unordered_map<uint32_t, FixedRgb> sums;
    for (auto pixel : result.getFilm()) {
      checkFilmValue(pixel, target.pixelCount);
      if (!sums[pixel.getPixel()].addWithinRange(FixedRgb{pixel.getR(), pixel.getG(), pixel.getB()}))
        throw FilmRangeError();
    }
    store.addFilm(target.job, sums, target.pixelCount);
  }
}

}  // namespace portico
