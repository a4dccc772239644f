#include "worker/lease_runner.h"

#include <spdlog/spdlog.h>

#include <chrono>

#include "worker/lease_load.h"
#include "worker/lease_result.h"
#include "worker/lease_trace.h"
#include "worker/test_faults.h"

namespace portico {

std::string photonTableOf(wire::PhotonsReply::Reader reply) {
  size_t size = 0;
  for (auto blob : reply.getBatches()) size += blob.size();
  std::string records;
  records.reserve(size);
  for (auto blob : reply.getBatches()) records.append(reinterpret_cast<const char*>(blob.begin()), blob.size());
  return records;
}

std::unique_ptr<capnp::MallocMessageBuilder> runLease(CellCache& cache, AcceleratorChooser& chooser,
                                                      wire::Assign::Reader assign,
                                                      std::optional<std::string> photonRecords,
                                                      const std::string& storeDirectory, int64_t forwardRays,
                                                      const std::atomic<bool>* stop,
                                                      std::atomic<uint64_t>* progress) {
  const auto started = std::chrono::steady_clock::now();
  const ThreadTimes startedTimes = threadTimes();
  stallIfTestFault();
  const LoadedLease lease = loadLease(cache, chooser, assign, std::move(photonRecords), storeDirectory);
  if (progress) progress->fetch_add(1, std::memory_order_relaxed);
  TracedLease traced = traceLoadedLease(cache, chooser, lease, assign, forwardRays, stop, progress);
  LeaseFigures figures;
  figures.cache = cache.takeStatistics();
  figures.irradiancePoints = lease.irradiancePoints;
  figures.irradianceMicroseconds = lease.irradianceMicroseconds;
  figures.forwarded = traced.forwarded;
  figures.moreCells = int64_t(assign.getMoreCells().size());
  figures.started = started;
  figures.startedTimes = startedTimes;
  applyTestFault(traced.out, lease.renderPhase);
  auto message = encodeResult(assign, traced.out, figures);
  applyTestFault(message->getRoot<wire::Envelope>().getResult());
  spdlog::debug("lease {} cell {}: {} batches, {} deposits, {} crossing cells, {} pixels in {:.1f} ms",
                assign.getLease(), assign.getCell(), assign.getBatches().size(), traced.out.counters.photonDeposits,
                traced.out.crossings.size(), traced.out.film.sums().size(),
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started).count());
  return message;
}

}  // namespace portico
