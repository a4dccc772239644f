#include "coordinator/cli/bench/simulated_result.h"

#include <algorithm>
#include <optional>
#include <cmath>
#include <string>
#include <string_view>
#include <utility>

#include "common/transport/film.h"
#include "common/transport/trace_counters.h"
#include "worker/deposit_region_writer.h"

namespace portico::cli {

CellNeighbours::CellNeighbours(size_t cellCount, const std::vector<Portal>& portals) : neighbours_(cellCount) {
  for (const Portal& portal : portals) {
    if (portal.cellA >= neighbours_.size() || portal.cellB >= neighbours_.size()) continue;
    neighbours_[portal.cellA].push_back(portal.cellB);
    neighbours_[portal.cellB].push_back(portal.cellA);
  }
}

uint32_t CellNeighbours::neighbour(uint32_t cell, uint64_t path) const {
  if (cell >= neighbours_.size() || neighbours_[cell].empty()) return cell;
  const auto& around = neighbours_[cell];
  return around[path % around.size()];
}

void SimulatedTally::add(const SimulatedTally& o) {
  results += o.results, emitted += o.emitted, photonsHandedOn += o.photonsHandedOn;
  depositRecords += o.depositRecords, cameraRays += o.cameraRays, raysHandedOn += o.raysHandedOn;
  regionRecords += o.regionRecords;
}

namespace {
// A ray handed on: only what the coordinator stores and forwards matters,
// not where it points.
struct HandedOn {
  uint64_t path = 0;
  uint32_t pixel = 0;
  uint16_t depth = 0;
};

// Whole counts from fractional rates, the same for the same lease: a
// running remainder, so that a shape of 0.13 hands on 13 of every 100.
class Rate {
 public:
  explicit Rate(double rate) : rate_(rate) {}
  int64_t take(int64_t started) {
    owed_ += rate_ * double(started);
    const auto whole = int64_t(std::floor(owed_));
    owed_ -= double(whole);
    return whole;
  }
  bool takeOne() { return take(1) > 0; }

 private:
  double rate_, owed_ = 0;
};

struct LeaseWalk {
  LeaseWalk(const ResultShape& shape, const CellNeighbours& neighbours, bool render, uint32_t spp)
      : shape(shape), neighbours(neighbours), render(render), spp(spp),
        crossings(render ? shape.cameraCrossings : shape.photonCrossings), depositRate(shape.depositsPerPhoton) {}
  const ResultShape& shape;
  const CellNeighbours& neighbours;
  bool render = false;
  uint32_t spp = 1;
  Rate crossings, depositRate;
  int64_t started = 0, emitted = 0, camera = 0, received = 0, sensors = 0;
  std::map<uint32_t, std::vector<HandedOn>> handedOn;   // by destination cell
  std::map<uint32_t, std::vector<PhotonRecord>> deposits;
  std::vector<std::pair<uint32_t, int64_t>> film;       // pixel, samples

  void handOn(uint32_t cell, const HandedOn& ray) {
    handedOn[neighbours.neighbour(cell, ray.path)].push_back(ray);
  }

  // A cell's batches (its own, or one of moreCells).
  void walk(uint32_t cell, capnp::List<wire::RayBatch>::Reader batches) {
    int64_t cellStarted = 0;
    for (const auto batch : batches) switch (batch.which()) {
        case wire::RayBatch::EMIT: {
          const auto emit = batch.getEmit();
          emitted += emit.getCount();
          cellStarted += emit.getCount();
          const int64_t out = crossings.take(emit.getCount());
          for (int64_t i = 0; i < out; ++i) handOn(cell, {emit.getFirstPath() + uint64_t(i), 0, 1});
          break;
        }
        case wire::RayBatch::CAMERA: {
          const auto range = batch.getCamera();
          const int64_t samples = int64_t(range.getPixelCount()) * spp;
          camera += samples;
          cellStarted += samples;
          for (uint32_t p = 0; p < range.getPixelCount(); ++p) film.emplace_back(range.getFirstPixel() + p, spp);
          const int64_t out = crossings.take(samples);
          for (int64_t i = 0; i < out; ++i) {
            const uint32_t pixel = range.getFirstPixel() + uint32_t(i % std::max<uint32_t>(1, range.getPixelCount()));
            handOn(cell, {uint64_t(pixel) * spp, pixel, 1});
          }
          break;
        }
        case wire::RayBatch::SENSORS: {
          const int64_t count = batch.getSensors().size();
          sensors += count;
          camera += count * spp;
          cellStarted += count * spp;
          break;
        }
        case wire::RayBatch::RAYS: {
          for (const auto ray : batch.getRays()) {
            ++received;
            ++cellStarted;
            const uint16_t depth = ray.getDepth() & 0x7fff;
            if (depth + 1u < shape.maxDepth && crossings.takeOne())
              handOn(cell, {ray.getPathId(), ray.getPixel(), uint16_t(depth + 1)});
          }
          break;
        }
      }
    if (!render) {
      const int64_t records = depositRate.take(cellStarted);
      if (records > 0) {
        auto& table = deposits[cell];
        table.resize(size_t(records));
        for (int64_t i = 0; i < records; ++i) table[size_t(i)] = PhotonRecord{uint64_t(i)};
      }
    }
    started += cellStarted;
  }
};

void setCounter(capnp::List<wire::Counter>::Builder counters, unsigned& at, std::string_view name, int64_t value) {
  counters[at].setName(std::string(name));
  counters[at].setValue(value);
  ++at;
}
}  // namespace

namespace {
// The lease's deposits written into its deposit region as a worker on the
// coordinator's file system writes them (worker/deposit_region_writer.h):
// per cell, where its records lie, or nothing for those that stay in the Result.
std::optional<DepositRegionWriter::Written> writeToRegion(wire::Assign::Reader assign,
                                                          const std::map<uint32_t, std::vector<PhotonRecord>>& deposits) {
  if (!assign.hasDepositRegion() || deposits.empty()) return std::nullopt;
  auto written = depositRegionWriter().write(assign.getDepositRegion(), assign.getJob(), assign.getLease(), deposits);
  if (!written) return std::nullopt;
  std::string error;
  if (!depositRegionWriter().finish(assign.getLease(), error)) return std::nullopt;
  return written;
}
}  // namespace

SimulatedResult simulateResult(wire::Assign::Reader assign, const ResultShape& shape, const CellNeighbours& neighbours,
                               bool useDepositRegion) {
  const bool render = assign.getPhase() == wire::Phase::RENDER;
  LeaseWalk walk(shape, neighbours, render, std::max<uint32_t>(1, assign.getSpec().getSpp()));
  walk.walk(assign.getCell(), assign.getBatches());
  for (const auto more : assign.getMoreCells()) walk.walk(more.getCell(), more.getBatches());

  SimulatedResult out;
  out.message = std::make_unique<capnp::MallocMessageBuilder>();
  auto result = out.message->initRoot<wire::Envelope>().initResult();
  result.setLease(assign.getLease());
  int64_t handedOn = 0;
  auto crossings = result.initCrossings(unsigned(walk.handedOn.size()));
  unsigned c = 0;
  for (const auto& [cell, rays] : walk.handedOn) {
    crossings[c].setCell(cell);
    auto list = crossings[c].initRays(unsigned(rays.size()));
    for (size_t i = 0; i < rays.size(); ++i) {
      auto ray = list[unsigned(i)];
      ray.setKind(render ? wire::RayKind::CAMERA : wire::RayKind::PHOTON);
      ray.setDepth(rays[i].depth);
      ray.setPathId(rays[i].path);
      ray.setPixel(rays[i].pixel);
      ray.setDz(1.0f);
      ray.setTMax(1e30f);
      ray.setR(1.0f), ray.setG(1.0f), ray.setB(1.0f);
    }
    handedOn += int64_t(rays.size());
    ++c;
  }
  const auto written = useDepositRegion ? writeToRegion(assign, walk.deposits) : std::nullopt;
  if (written) result.setRegionNonce(capnp::Data::Reader(written->nonce.data(), written->nonce.size()));
  int64_t records = 0;
  auto deposits = result.initDeposits(unsigned(walk.deposits.size()));
  unsigned d = 0;
  for (const auto& [cell, table] : walk.deposits) {
    deposits[d].setCell(cell);
    if (written && written->extents[d]) {
      deposits[d].setFileOffset(written->extents[d]->offset);
      deposits[d].setFileSize(written->extents[d]->size);
      deposits[d].setFileCrc(written->extents[d]->crc);
      out.tally.regionRecords += int64_t(table.size());
    } else {
      deposits[d].setRecords(capnp::Data::Reader(reinterpret_cast<const kj::byte*>(table.data()),
                                                 table.size() * sizeof(PhotonRecord)));
    }
    records += int64_t(table.size());
    ++d;
  }
  // A film value per camera sample's pixel, well inside the film's range.
  auto film = result.initFilm(unsigned(walk.film.size()));
  for (size_t i = 0; i < walk.film.size(); ++i) {
    film[unsigned(i)].setPixel(walk.film[i].first);
    const int64_t value = walk.film[i].second * (int64_t(1) << 20);
    film[unsigned(i)].setR(value), film[unsigned(i)].setG(value), film[unsigned(i)].setB(value);
  }
  const int64_t work = std::max<int64_t>(1, assign.getLeaseWork());
  const int64_t leaseMicros = std::max<int64_t>(1000, std::llround(double(work) * 1e6 / shape.raysPerSecond));
  auto counters = result.initCounters(10);
  unsigned at = 0;
  if (render) {
    setCounter(counters, at, "rays.camera", walk.camera);
    setCounter(counters, at, "rays.finished", walk.started - handedOn);
    setCounter(counters, at, "rays.crossings", handedOn);
    setCounter(counters, at, "sensors.measured", walk.sensors);
    setCounter(counters, at, "rays.traced", walk.started);
  } else {
    setCounter(counters, at, "photons.emitted", walk.emitted);
    setCounter(counters, at, "photons.absorbed", walk.started - handedOn - (shape.miscount ? 1 : 0));
    setCounter(counters, at, "photons.crossings", handedOn);
    setCounter(counters, at, "photons.deposits", records);
    setCounter(counters, at, "rays.traced", walk.started);
  }
  setCounter(counters, at, "rays.invalid", 0);
  setCounter(counters, at, kLeaseTimeCounter, leaseMicros);
  setCounter(counters, at, kLeaseCpuCounter, leaseMicros);
  setCounter(counters, at, kPeakResidentCounter, int64_t(64) << 20);
  setCounter(counters, at, "cells.loaded", 0);
  out.tally.results = 1;
  out.tally.emitted = walk.emitted;
  out.tally.cameraRays = walk.camera;
  out.tally.depositRecords = records;
  (render ? out.tally.raysHandedOn : out.tally.photonsHandedOn) = handedOn;
  return out;
}

}  // namespace portico::cli
