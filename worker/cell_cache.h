// The worker's memory: loaded cells (mapped geometry + accelerator) and
// photon maps with their irradiance caches, least recently used evicted
// first, under a byte budget.
#pragma once

#include <cstdint>
#include <functional>
#include <list>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "common/accel/accelerator.h"
#include "common/scene/store/cell_geometry.h"
#include "common/scene/store/scene_store.h"
#include "common/transport/cell_tracer.h"
#include "common/transport/indirect_light.h"

namespace portico {

struct LoadedCell {
  std::unique_ptr<CellGeometry> geometry;
  std::unique_ptr<Accelerator> accelerator;
  std::unique_ptr<CellTracer> tracer;
  std::string builtSpec;     // what was built: the requested spec, or auto's choice
  int64_t raysTraced = 0;    // since it was loaded (logged with auto's rebuilds)
  uint64_t bytes() const { return geometry->bytes() + accelerator->stats().bytes; }
};

// Which photon map: the job whose photon tables it is built from (the
// lease's own job, or the earlier job whose photon pass it reuses), the
// cell, and how it is built from them (photonMapBuild, lease_load.h): jobs
// that share a photon pass may keep different photons or precompute
// irradiance with another k.
struct PhotonMapKey {
  uint64_t photonJob = 0;
  uint32_t cell = 0;
  uint32_t build = 0;
  auto operator<=>(const PhotonMapKey&) const = default;
};

struct CacheStatistics {
  int64_t cellsLoaded = 0, cellHits = 0, bytesRead = 0, photonMapsBuilt = 0;
  double acceleratorBuildMs = 0;
  // Loads only: their triangles, and their time (read, validation and build).
  int64_t trianglesLoaded = 0;
  double loadMs = 0;
  std::vector<std::pair<uint32_t, std::string>> builds;   // (cell, spec) of each accelerator built
};

// The budget bounds what the cache holds *and* what it is about to load:
// room is made before a cell is read and its accelerator built (from an
// estimate that learns from the cells loaded so far), so the worker's peak
// stays near the budget instead of budget + one cell + build scratch.
// Entries used by the current lease are pinned and never evicted under it.
//
// The entries' own count is not all a worker holds: freed memory the heap
// keeps (a photon map's assembly leaves twice the map's size of freed
// arrays resident), the lease's messages and the code. With a resident
// limit, making room also brings the process's measured resident size
// plus what is about to be loaded under that limit: the heap's free pages
// are given back first, then entries evicted until it fits.
class CellCache {
 public:
  // budgetBytes: what the entries may hold. residentLimitBytes: the
  // process's resident size that a load may bring it to (0: unchecked).
  explicit CellCache(uint64_t budgetBytes, uint64_t residentLimitBytes = 0)
      : budget_(budgetBytes), residentLimit_(residentLimitBytes) {}

  const SceneStore& scene(const std::string& directory);
  // A new lease: what the previous one pinned may go again.
  void beginLease() { ++epoch_; }
  // Loads (or finds) the cell and its accelerator for the given spec; pinned.
  // When the cell must be loaded and `resolve` is given, the accelerator
  // built is resolve()'s spec (`auto`'s choice); the entry stays keyed by
  // acceleratorSpec.
  LoadedCell& cell(const std::string& directory, uint32_t cell, const std::string& acceleratorSpec,
                   const std::function<std::string()>& resolve = {});
  // The cell if it is held with this spec (then pinned), else null: loads nothing.
  LoadedCell* heldCell(const std::string& directory, uint32_t cell, const std::string& acceleratorSpec);
  // Replaces a loaded cell's accelerator with one built from `spec`.
  void rebuildAccelerator(LoadedCell& cell, const std::string& spec);
  // The photon map (and irradiance cache) under `key`, or nullptr when not cached; pinned.
  const IndirectLight* indirectLight(const PhotonMapKey& key);
  const IndirectLight& storeIndirectLight(const PhotonMapKey& key, std::unique_ptr<IndirectLight> light);
  // Evicts unpinned entries, least recently used first, until `bytes` more
  // fit in the budget and, with a resident limit, in it beside the
  // process's resident size (or nothing unpinned is left).
  void makeRoom(uint64_t bytes);

  CacheStatistics takeStatistics();
  uint64_t bytesHeld() const { return held_; }
  uint64_t budget() const { return budget_; }
  uint64_t residentLimit() const { return residentLimit_; }

 private:
  using CellKey = std::tuple<std::string, uint32_t, std::string>;
  using MapKey = PhotonMapKey;
  struct Entry {
    std::unique_ptr<LoadedCell> cell;
    std::unique_ptr<IndirectLight> map;
    uint64_t bytes = 0;
    uint64_t pinnedEpoch = 0;
    std::optional<CellKey> cellKey;   // which map owns it, for O(log n) eviction
    std::optional<MapKey> mapKey;
    std::list<Entry*>::iterator position;
  };
  void prepareTextures(const SceneStore& scene);
  void touch(Entry& entry);
  void insert(Entry& entry);
  void evict(Entry* victim);
  // Evicts unpinned entries, least recently used first, until `enough`
  // (given the bytes evicted so far) holds; returns the bytes evicted.
  uint64_t evictUntil(const std::function<bool(uint64_t evicted)>& enough);
  void buildAccelerator(LoadedCell& cell, const std::string& spec);

  uint64_t budget_;
  uint64_t residentLimit_;
  bool saidOverLimit_ = false;
  uint64_t held_ = 0;
  bool texturesCharged_ = false;   // the texture module's memory taken from budget_
  std::string texturesRefused_;     // why textured stores cannot be traced (budget too small), or empty
  uint64_t epoch_ = 1;
  double loadedBytesPerFileByte_ = 3.0;   // learnt: geometry + accelerator + build scratch per file byte
  std::map<std::string, std::unique_ptr<SceneStore>> scenes_;
  std::map<CellKey, Entry> cells_;
  std::map<MapKey, Entry> maps_;
  std::list<Entry*> recency_;   // front: most recent
  CacheStatistics statistics_;
};

}  // namespace portico
