// Writes one cell file (proto::CellFile, unpacked Cap'n Proto) so that
// CellGeometry can mmap it and read it in place. Private to the scene store:
// SceneStoreWriter validates the content before calling this.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/scene/store/scene_store.h"
#include "common/scene/store/scene_types.h"

namespace portico {

// The most elements a bulk-list chunk may hold: Cap'n Proto lists hold fewer
// than 2^29 elements; staying under 2^28 leaves room and keeps chunks
// reasonably sized for a reader that copies them.
constexpr uint64_t kMaxCellChunkElements = (uint64_t{1} << 28) - 1;

// Writes `cell` and the portals touching it to `path` (created or
// truncated) with bulk arrays cut into chunks of at most maxChunkElements
// elements (whole vertices / triangles per chunk). Returns the file size.
// Throws std::runtime_error naming the path on I/O errors.
uint64_t writeCellFile(const std::string& path, const CellContent& cell, const std::vector<const Portal*>& portals,
                       uint64_t maxChunkElements = kMaxCellChunkElements);

}  // namespace portico
