#include "worker/cell_cache.h"

#include <chrono>

#include <fmt/format.h>
#include <malloc.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <stdexcept>

#include "common/transport/albedo_texture.h"
#include "common/util/resident_memory.h"

namespace portico {

const SceneStore& CellCache::scene(const std::string& directory) {
  auto it = scenes_.find(directory);
  if (it == scenes_.end())
    it = scenes_.emplace(directory, std::make_unique<SceneStore>(SceneStore::open(directory))).first;
  prepareTextures(*it->second);
  return *it->second;
}

// The texture module's code (OpenImageIO and the libraries it pulls in:
// about 118 MiB resident) and its tile cache (at most cacheBytes()) come out
// of the budget, once, when the first store with a textured material
// arrives: a worker that never meets a texture never loads OpenImageIO. A
// budget too small for them refuses every lease of a textured store.
void CellCache::prepareTextures(const SceneStore& scene) {
  if (std::none_of(scene.materials().begin(), scene.materials().end(), [](const Material& m) { return m.textured(); }))
    return;
  if (!texturesCharged_) {
    texturesCharged_ = true;
    AlbedoTextures& textures = AlbedoTextures::instance();
    const uint64_t before = residentBytes();
    textures.load();
    const uint64_t after = residentBytes();
    const uint64_t code = after > before ? after - before : 0;
    const uint64_t cost = code + textures.cacheBytes();
    constexpr uint64_t kLeastForCells = uint64_t(4) << 20;
    if (cost + kLeastForCells > budget_) {
      texturesRefused_ = fmt::format(
          "the worker's --memory is too small for textures: the texture module takes {} MiB and its tile cache {} "
          "MiB, of a cell cache budget of {} MiB (give the worker {} MiB more)",
          code >> 20, textures.cacheBytes() >> 20, budget_ >> 20, (cost + kLeastForCells - budget_ + (1 << 20)) >> 20);
      budget_ = kLeastForCells;
    } else {
      budget_ -= cost;
    }
    spdlog::info("textures: module {} MiB, tile cache {} MiB; cell cache budget now {} MiB", code >> 20,
                 textures.cacheBytes() >> 20, budget_ >> 20);
  }
  if (!texturesRefused_.empty())
    throw std::runtime_error(fmt::format("store {} has textures, and {}", scene.directory(), texturesRefused_));
}

void CellCache::touch(Entry& entry) {
  recency_.splice(recency_.begin(), recency_, entry.position);
  entry.pinnedEpoch = epoch_;
}

void CellCache::insert(Entry& entry) {
  recency_.push_front(&entry);
  entry.position = recency_.begin();
  entry.pinnedEpoch = epoch_;
  held_ += entry.bytes;
}

void CellCache::evict(Entry* victim) {
  recency_.erase(victim->position);
  held_ -= victim->bytes;
  if (victim->cellKey)
    cells_.erase(*victim->cellKey);
  else if (victim->mapKey)
    maps_.erase(*victim->mapKey);
}

uint64_t CellCache::evictUntil(const std::function<bool(uint64_t evicted)>& enough) {
  uint64_t evicted = 0;
  for (auto it = recency_.end(); it != recency_.begin() && !enough(evicted);) {
    --it;
    Entry* entry = *it;
    if (entry->pinnedEpoch == epoch_) continue;   // the lease in progress uses it
    it = std::next(it);
    evicted += entry->bytes;
    evict(entry);
  }
  return evicted;
}

void CellCache::makeRoom(uint64_t bytes) {
  bool trimmed = false;
  // Give freed pages back to the system, so that the worker's resident
  // size follows what the cache holds.
  if (evictUntil([&](uint64_t) { return held_ + bytes <= budget_; }) > 0) {
    ::malloc_trim(0);
    trimmed = true;
  }
  if (residentLimit_ == 0) return;
  uint64_t resident = residentBytes();
  while (resident + bytes > residentLimit_) {
    if (!trimmed) {
      // The heap's free pages first: they cost a page fault when used again,
      // a reload costs the cell.
      ::malloc_trim(0);
      trimmed = true;
    } else {
      const uint64_t excess = resident + bytes - residentLimit_;
      if (evictUntil([&](uint64_t evicted) { return evicted >= excess; }) == 0) {
        // What is left is the lease's own: it goes ahead, over the limit,
        // and says so (once: a budget this tight says it on every load).
        if (!saidOverLimit_)
          spdlog::warn("--memory is too small for this lease: {} MiB resident and {} MiB to load exceed the {} MiB "
                       "a load may bring the worker to (--memory less a lease's buffers), and only the lease's own "
                       "cells and photon maps are left to evict",
                       resident >> 20, bytes >> 20, residentLimit_ >> 20);
        saidOverLimit_ = true;
        return;
      }
      ::malloc_trim(0);
    }
    resident = residentBytes();
  }
}

LoadedCell& CellCache::cell(const std::string& directory, uint32_t cellId, const std::string& acceleratorSpec,
                            const std::function<std::string()>& resolve) {
  CellKey key{directory, cellId, acceleratorSpec};
  if (auto it = cells_.find(key); it != cells_.end()) {
    touch(it->second);
    ++statistics_.cellHits;
    return *it->second.cell;
  }
  const SceneStore& store = scene(directory);
  if (cellId >= store.cells().size())
    throw std::runtime_error("cell " + std::to_string(cellId) + " does not exist in " + directory);
  const uint64_t fileBytes = store.cells()[cellId].byteCount;
  makeRoom(uint64_t(loadedBytesPerFileByte_ * double(fileBytes)));
  const auto started = std::chrono::steady_clock::now();
  auto loaded = std::make_unique<LoadedCell>();
  loaded->geometry = CellGeometry::load(store.cellPath(cellId), cellId, store.materials().size());
  buildAccelerator(*loaded, resolve ? resolve() : acceleratorSpec);
  statistics_.loadMs += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started).count();
  statistics_.trianglesLoaded += int64_t(loaded->geometry->mesh().triangleCount);
  ++statistics_.cellsLoaded;
  statistics_.bytesRead += loaded->geometry->bytes();
  // Learn the ratio (with a margin for the build's scratch memory).
  if (fileBytes > (64u << 10))
    loadedBytesPerFileByte_ = std::max(loadedBytesPerFileByte_, 1.5 * double(loaded->bytes()) / double(fileBytes));
  Entry& entry = cells_[key];
  entry.bytes = loaded->bytes();
  entry.cell = std::move(loaded);
  entry.cellKey = key;
  insert(entry);
  return *entry.cell;
}

LoadedCell* CellCache::heldCell(const std::string& directory, uint32_t cellId, const std::string& acceleratorSpec) {
  auto it = cells_.find(CellKey{directory, cellId, acceleratorSpec});
  if (it == cells_.end()) return nullptr;
  touch(it->second);
  return it->second.cell.get();
}

void CellCache::buildAccelerator(LoadedCell& cell, const std::string& spec) {
  cell.tracer.reset();
  cell.accelerator.reset();
  cell.accelerator = portico::buildAccelerator(parseAcceleratorSpec(spec), cell.geometry->mesh());
  cell.tracer = std::make_unique<CellTracer>(*cell.geometry, *cell.accelerator);
  cell.builtSpec = spec;
  const uint32_t id = cell.geometry->id();
  statistics_.acceleratorBuildMs += cell.accelerator->stats().buildMs;
  statistics_.builds.emplace_back(id, spec);
  spdlog::debug("cell {} ({} triangles, {} bytes): {} built in {:.2f} ms", id, cell.geometry->mesh().triangleCount,
                cell.geometry->bytes(), spec, cell.accelerator->stats().buildMs);
}

void CellCache::rebuildAccelerator(LoadedCell& cell, const std::string& spec) {
  for (auto& [key, entry] : cells_) {
    if (entry.cell.get() != &cell) continue;
    makeRoom(entry.bytes);   // the new structure is of the old one's order; this cell is pinned
    held_ -= entry.bytes;
    buildAccelerator(cell, spec);
    entry.bytes = cell.bytes();
    held_ += entry.bytes;
    return;
  }
  throw std::logic_error("rebuildAccelerator: the cell is not in the cache");
}

const IndirectLight* CellCache::indirectLight(const PhotonMapKey& key) {
  auto it = maps_.find(key);
  if (it == maps_.end()) return nullptr;
  touch(it->second);
  return it->second.map.get();
}

const IndirectLight& CellCache::storeIndirectLight(const PhotonMapKey& key, std::unique_ptr<IndirectLight> map) {
  Entry& entry = maps_[key];
  if (entry.map) {
    held_ -= entry.bytes;
    recency_.erase(entry.position);
  }
  entry.bytes = map->bytes();
  entry.map = std::move(map);
  entry.mapKey = key;
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
