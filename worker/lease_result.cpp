#include "worker/lease_result.h"

#include "worker/deposit_region_writer.h"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <deque>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "common/net/ray_wire.h"
#include "common/transport/photon_record.h"
#include "common/util/process_memory.h"

namespace portico {

namespace {
void encodeCrossings(const KernelOutputs& out, wire::Result::Builder result) {
  auto crossings = result.initCrossings(static_cast<unsigned>(out.crossings.size()));
  unsigned c = 0;
  for (const auto& [destination, rays] : out.crossings) {
    crossings[c].setCell(destination);
    auto list = crossings[c].initRays(static_cast<unsigned>(rays.size()));
    for (size_t i = 0; i < rays.size(); ++i) toWire(rays[i], list[static_cast<unsigned>(i)]);
    ++c;
  }
}

void encodeDeposits(wire::Assign::Reader assign, const KernelOutputs& out, wire::Result::Builder result) {
  std::optional<DepositRegionWriter::Written> written;
  if (assign.hasDepositRegion() && !out.deposits.empty())
    written = depositRegionWriter().write(assign.getDepositRegion(), assign.getJob(), assign.getLease(), out.deposits);
  if (written)
    result.setRegionNonce(capnp::Data::Reader(written->nonce.data(), written->nonce.size()));
  auto deposits = result.initDeposits(static_cast<unsigned>(out.deposits.size()));
  unsigned d = 0;
  for (const auto& [cell, records] : out.deposits) {
    deposits[d].setCell(cell);
    if (written && written->extents[d]) {
      const DepositRegionWriter::Extent& extent = *written->extents[d];
      deposits[d].setFileOffset(extent.offset);
      deposits[d].setFileSize(extent.size);
      deposits[d].setFileCrc(extent.crc);
    } else {
      deposits[d].setRecords(capnp::Data::Reader(reinterpret_cast<const kj::byte*>(records.data()),
                                                 records.size() * sizeof(PhotonRecord)));
    }
    ++d;
  }
}

void encodeFilm(const KernelOutputs& out, wire::Result::Builder result) {
  auto film = result.initFilm(static_cast<unsigned>(out.film.sums().size()));
  unsigned f = 0;
  for (const auto& [pixel, rgb] : out.film.sums()) {
    film[f].setPixel(pixel);
    film[f].setR(rgb.r);
    film[f].setG(rgb.g);
    film[f].setB(rgb.b);
    ++f;
  }
}

void encodeCounters(const KernelOutputs& out, const LeaseFigures& figures, wire::Result::Builder result) {
  const CacheStatistics& cache = figures.cache;
  auto named = out.counters.named();
  named.push_back({"cells.loaded", cache.cellsLoaded});
  named.push_back({"cells.cache_hits", cache.cellHits});
  named.push_back({"cells.bytes_read", cache.bytesRead});
  named.push_back({"photon_maps.built", cache.photonMapsBuilt});
  named.push_back({"irradiance.points", figures.irradiancePoints});
  named.push_back({"time.irradiance_us", figures.irradianceMicroseconds});
  named.push_back({"rays.forwarded", figures.forwarded});
  named.push_back({"leases.extra_cells", figures.moreCells});
  // Microseconds: most builds take well under a millisecond.
  named.push_back({"time.accel_build_us", std::llround(cache.acceleratorBuildMs * 1e3)});
  // What loading a cell costs this worker: the coordinator weighs a second
  // copy of a cell by it (chooseCell).
  named.push_back({std::string_view(kLoadTimeCounter), std::llround(cache.loadMs * 1e3)});
  named.push_back({std::string_view(kTrianglesLoadedCounter), cache.trianglesLoaded});
  named.push_back({std::string_view(kPeakResidentCounter), int64_t(peakResidentBytes())});
  // The coordinator sizes this worker's leases from it (WorkerInfo::recordLease).
  named.push_back({std::string_view(kLeaseTimeCounter),
                   std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() -
                                                                         figures.started)
                       .count()});
  const ThreadTimes times = threadTimes();
  named.push_back({std::string_view(kLeaseCpuCounter), times.cpuMicros - figures.startedTimes.cpuMicros});
  if (times.runQueueMicros >= 0 && figures.startedTimes.runQueueMicros >= 0)
    named.push_back({std::string_view(kLeaseRunQueueCounter), times.runQueueMicros - figures.startedTimes.runQueueMicros});
  // Which structure each cell got (auto's choices): the job's statistics
  // list them per cell and count them per spec.
  std::deque<std::string> buildNames;   // owns the names `named` views
  for (const auto& [builtCell, builtSpec] : cache.builds) {
    named.push_back({buildNames.emplace_back("accel.built." + builtSpec), 1});
    named.push_back({buildNames.emplace_back(fmt::format("accel.cell.{}.{}", builtCell, builtSpec)), 1});
  }
  auto counters = result.initCounters(static_cast<unsigned>(named.size()));
  for (size_t i = 0; i < named.size(); ++i) {
    counters[static_cast<unsigned>(i)].setName(std::string(named[i].first));
    counters[static_cast<unsigned>(i)].setValue(named[i].second);
  }
}
}  // namespace

std::unique_ptr<capnp::MallocMessageBuilder> encodeResult(wire::Assign::Reader assign, const KernelOutputs& out,
                                                          const LeaseFigures& figures) {
  auto message = std::make_unique<capnp::MallocMessageBuilder>();
  auto result = message->initRoot<wire::Envelope>().initResult();
  result.setLease(assign.getLease());
  encodeCrossings(out, result);
  encodeDeposits(assign, out, result);
  encodeFilm(out, result);
  encodeCounters(out, figures, result);
  return message;
}

}  // namespace portico
