// Serves a scene store's files to workers that cannot see its file system
// (worker --cache-dir): scene.db, cells/<id>.cell and textures/<id>.tif of the stores of the
// jobs the asking worker holds leases of, nothing else, in chunks that fit
// a message. Each path is opened one component at a time from "/",
// following no symbolic link (above the store as well as in it), and only a
// regular file is served: a store cannot hand out a file outside itself,
// nor can a folder above it swapped for a link after submit.
#pragma once

#include <cstdint>
#include <set>
#include <string>

#include <capnp/message.h>

#include "common/scene/store/store_file_names.h"
#include "proto/wire.capnp.h"

namespace portico {

constexpr uint64_t kFileChunkBytes = uint64_t(4) << 20;

// Fills `chunk` for the request; a request outside `stores` (the resolved
// store directories the asker may read) or for another path, a symbolic
// link, anything but a regular file, or a file that cannot be read, gets
// an `error` naming it.
void serveFileChunk(const std::set<std::string>& stores, wire::FetchFile::Reader request,
                    wire::FileChunk::Builder chunk);

}  // namespace portico
