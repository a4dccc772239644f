// The worker's memory: loaded cells (mapped geometry + accelerator) and
// photon maps, least recently used evicted first, under a byte budget.
#pragma once

#include <cstdint>
#include <list>
#include <map>
#include <memory>
#include <string>
#include <tuple>

#include "common/accel/accelerator.h"
#include "common/scene/cell_geometry.h"
#include "common/scene/scene_store.h"
#include "common/transport/cell_tracer.h"
#include "common/transport/photon_map.h"

namespace portico {

struct LoadedCell {
  std::unique_ptr<CellGeometry> geometry;
  std::unique_ptr<Accelerator> accelerator;
  std::unique_ptr<CellTracer> tracer;
  uint64_t bytes() const { return geometry->bytes() + accelerator->stats().bytes; }
};

struct CacheStatistics {
  int64_t cellsLoaded = 0, cellHits = 0, bytesRead = 0, photonMapsBuilt = 0;
  double acceleratorBuildMs = 0;
};

class CellCache {
 public:
  explicit CellCache(uint64_t budgetBytes) : budget_(budgetBytes) {}

  const SceneStore& scene(const std::string& directory);
  // Loads (or finds) the cell and its accelerator for the given spec.
  const LoadedCell& cell(const std::string& directory, uint32_t cell, const std::string& acceleratorSpec);
  // The photon map of (job, cell), or nullptr when not cached.
  const PhotonMap* photonMap(uint64_t job, uint32_t cell);
  const PhotonMap& storePhotonMap(uint64_t job, uint32_t cell, std::unique_ptr<PhotonMap> map);

  CacheStatistics takeStatistics();
  uint64_t bytesHeld() const { return held_; }
  // Evicts least recently used entries until the cache holds at most `bytes`.
  void evictUntil(uint64_t bytes);

 private:
  using CellKey = std::tuple<std::string, uint32_t, std::string>;
  using MapKey = std::pair<uint64_t, uint32_t>;
  struct Entry {
    std::unique_ptr<LoadedCell> cell;
    std::unique_ptr<PhotonMap> map;
    uint64_t bytes = 0;
    std::list<Entry*>::iterator position;
  };
  void touch(Entry& entry);
  void insert(Entry& entry);

  uint64_t budget_;
  uint64_t held_ = 0;
  std::map<std::string, std::unique_ptr<SceneStore>> scenes_;
  std::map<CellKey, Entry> cells_;
  std::map<MapKey, Entry> maps_;
  std::list<Entry*> recency_;   // front: most recent
  CacheStatistics statistics_;
};

}  // namespace portico
