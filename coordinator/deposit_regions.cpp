#include "coordinator/deposit_regions.h"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

#include "common/transport/photon_record.h"

namespace portico {

int64_t depositRegionBytes(int64_t leaseWork, size_t cells) {
  constexpr int64_t block = deposit_region::kBlockBytes;
  const int64_t work = std::clamp<int64_t>(leaseWork, 1, kMostRegionBytes / kRegionBytesPerWork);
  const int64_t records = (work * kRegionBytesPerWork + block - 1) / block * block;
  return std::min(kMostRegionBytes, block + records + int64_t(std::max<size_t>(cells, 1)) * block);
}

std::vector<RegionDeposit> regionDeposits(uint64_t lease, const DepositRegionGrant* grant,
                                          wire::Result::Reader result, size_t cellCount) {
  std::vector<RegionDeposit> deposits;
  for (auto cellPhotons : result.getDeposits()) {
    if (cellPhotons.getFileSize() == 0) continue;
    if (cellPhotons.getCell() >= cellCount)
      throw std::runtime_error(fmt::format("result for lease {} deposits photons in cell {}, which does not exist",
                                           lease, cellPhotons.getCell()));
    if (cellPhotons.getRecords().size() != 0)
      throw std::runtime_error(fmt::format(
          "result for lease {} sends cell {}'s photons both in the result and in its deposit region", lease,
          cellPhotons.getCell()));
    deposits.push_back({cellPhotons.getCell(), FileExtent{int64_t(std::min<uint64_t>(cellPhotons.getFileOffset(), INT64_MAX)),
                                                          int64_t(std::min<uint64_t>(cellPhotons.getFileSize(), INT64_MAX)),
                                                          cellPhotons.getFileCrc()}});
  }
  if (deposits.empty() && result.getRegionNonce().size() == 0) return deposits;
  if (!grant) throw std::runtime_error(fmt::format("result for lease {} names a deposit region it was not given", lease));
  const auto nonce = result.getRegionNonce();
  if (nonce.size() != grant->nonce.size() || !std::equal(nonce.begin(), nonce.end(), grant->nonce.begin()))
    throw std::runtime_error(fmt::format(
        "result for lease {} does not return its deposit region's nonce (the worker did not read the region's head)",
        lease));
  const int64_t first = grant->offset + deposit_region::kBlockBytes, end = grant->offset + grant->size;
  for (const RegionDeposit& d : deposits) {
    const FileExtent& e = d.extent;
    if (e.size % int64_t(sizeof(PhotonRecord)) != 0)
      throw std::runtime_error(fmt::format("result for lease {} names {} bytes of cell {}'s photons, not whole records",
                                           lease, e.size, d.cell));
    if (e.offset < first || e.offset > end || e.size > end - e.offset)
      throw std::runtime_error(fmt::format(
          "result for lease {} names cell {}'s photons at offset {} ({} bytes), outside its deposit region [{}, {})",
          lease, d.cell, e.offset, e.size, first, end));
  }
  std::vector<const RegionDeposit*> byOffset;
  for (const RegionDeposit& d : deposits) byOffset.push_back(&d);
  std::sort(byOffset.begin(), byOffset.end(),
            [](const RegionDeposit* a, const RegionDeposit* b) { return a->extent.offset < b->extent.offset; });
  for (size_t i = 1; i < byOffset.size(); ++i)
    if (byOffset[i - 1]->extent.offset + byOffset[i - 1]->extent.size > byOffset[i]->extent.offset)
      throw std::runtime_error(fmt::format("result for lease {} names overlapping photons of cells {} and {} in its "
                                           "deposit region",
                                           lease, byOffset[i - 1]->cell, byOffset[i]->cell));
  return deposits;
}

}  // namespace portico
