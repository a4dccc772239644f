// A worker's disk cache of the scene stores it traces, fetched from the
// coordinator (portico-worker --cache-dir): no shared file system needed.
//
// Layout: DIR/<fnv64 of the store's name on the coordinator>/scene.db and
// cells/<id>.cell (and textures/<id>.tif), as in a store; files arrive as <path>.part and are
// renamed into place when whole, so a crash never leaves a torn file that
// looks complete. scene.db is fetched again at a worker's first lease of a
// store: if it changed (the store was regenerated), the cached cells go.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>

#include "common/scene/store/scene_store.h"
#include "proto/wire.capnp.h"

namespace portico {

class StoreMirror {
 public:
  explicit StoreMirror(std::string cacheDirectory);

  // The local directory holding the copy of `store`.
  std::string localDirectory(const std::string& store) const;
  // The next file a lease of `cell` needs and lacks; nullopt when ready.
  std::optional<std::string> missing(const std::string& store, uint32_t cell);
  // Bytes of `path` received so far (the offset to ask for next).
  uint64_t receivedBytes(const std::string& store, const std::string& path) const;
  // Writes a chunk; true when it completed its file. Throws naming the
  // file when the coordinator sent an error or a chunk out of order.
  bool accept(wire::FileChunk::Reader chunk);
  uint64_t bytesFetched() const { return bytesFetched_; }

 private:
  struct StoreState {
    bool catalogueFresh = false;              // scene.db fetched by this process
    std::unique_ptr<SceneStore> catalogue;
  };
  StoreState& state(const std::string& store);

  std::string root_;
  std::map<std::string, StoreState> stores_;
  uint64_t bytesFetched_ = 0;
};

}  // namespace portico
