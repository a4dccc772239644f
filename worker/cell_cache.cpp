#include "worker/cell_cache.h"

#include <spdlog/spdlog.h>

namespace portico {

const SceneStore& CellCache::scene(const std::string& directory) {
  auto it = scenes_.find(directory);
  if (it == scenes_.end())
    it = scenes_.emplace(directory, std::make_unique<SceneStore>(SceneStore::open(directory))).first;
  return *it->second;
}

void CellCache::touch(Entry& entry) { recency_.splice(recency_.begin(), recency_, entry.position); }

void CellCache::insert(Entry& entry) {
  recency_.push_front(&entry);
  entry.position = recency_.begin();
  held_ += entry.bytes;
  // Keep the newest entry even when it alone exceeds the budget: the lease
  // needs it; everything older goes first.
  evictUntil(budget_ > entry.bytes ? budget_ : entry.bytes);
}

void CellCache::evictUntil(uint64_t bytes) {
  while (held_ > bytes && recency_.size() > 1) {
    Entry* victim = recency_.back();
    recency_.pop_back();
    held_ -= victim->bytes;
    // Find and erase the owner map entry.
    for (auto it = cells_.begin(); it != cells_.end(); ++it)
      if (&it->second == victim) {
        cells_.erase(it);
        victim = nullptr;
        break;
      }
    if (victim)
      for (auto it = maps_.begin(); it != maps_.end(); ++it)
        if (&it->second == victim) {
          maps_.erase(it);
          break;
        }
  }
}

const LoadedCell& CellCache::cell(const std::string& directory, uint32_t cellId, const std::string& acceleratorSpec) {
  CellKey key{directory, cellId, acceleratorSpec};
  if (auto it = cells_.find(key); it != cells_.end()) {
    touch(it->second);
    ++statistics_.cellHits;
    return *it->second.cell;
  }
  const SceneStore& store = scene(directory);
  if (cellId >= store.cells().size())
    throw std::runtime_error("cell " + std::to_string(cellId) + " does not exist in " + directory);
  auto loaded = std::make_unique<LoadedCell>();
  loaded->geometry = CellGeometry::load(store.cellPath(cellId), cellId, store.materials().size());
  loaded->accelerator = buildAccelerator(parseAcceleratorSpec(acceleratorSpec), loaded->geometry->mesh());
  loaded->tracer = std::make_unique<CellTracer>(*loaded->geometry, *loaded->accelerator);
  ++statistics_.cellsLoaded;
  statistics_.bytesRead += loaded->geometry->bytes();
  statistics_.acceleratorBuildMs += loaded->accelerator->stats().buildMs;
  spdlog::debug("loaded cell {} ({} triangles, {} bytes), {} built in {:.2f} ms", cellId,
                loaded->geometry->mesh().triangleCount, loaded->geometry->bytes(), acceleratorSpec,
                loaded->accelerator->stats().buildMs);
  Entry& entry = cells_[key];
  entry.bytes = loaded->bytes();
  entry.cell = std::move(loaded);
  insert(entry);
  return *entry.cell;
}

const PhotonMap* CellCache::photonMap(uint64_t job, uint32_t cell) {
  auto it = maps_.find({job, cell});
  if (it == maps_.end()) return nullptr;
  touch(it->second);
  return it->second.map.get();
}

const PhotonMap& CellCache::storePhotonMap(uint64_t job, uint32_t cell, std::unique_ptr<PhotonMap> map) {
  Entry& entry = maps_[{job, cell}];
  if (entry.map) {
    held_ -= entry.bytes;
    recency_.erase(entry.position);
  }
  entry.bytes = map->bytes();
  entry.map = std::move(map);
  ++statistics_.photonMapsBuilt;
  insert(entry);
  return *entry.map;
}

CacheStatistics CellCache::takeStatistics() {
  CacheStatistics s = statistics_;
  statistics_ = {};
  return s;
}

}  // namespace portico
