// CellGeometry: a cell file mmap'd and read in place with Cap'n Proto's
// FlatArrayMessageReader. A bulk array stored as one chunk is used where it
// lies in the mapping (zero copy); one split over several chunks is joined
// into a vector, because accelerators want one contiguous array.
#include "common/scene/store/cell_geometry.h"

#include <capnp/any.h>
#include <capnp/serialize.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <kj/exception.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "proto/scene.capnp.h"

namespace portico {

static_assert(std::endian::native == std::endian::little, "cell files are read in place: little-endian only");

namespace {

// A problem with the file's content; load() prefixes the path.
std::runtime_error malformed(const std::string& problem) { return std::runtime_error(problem); }

// The chunks of a bulk array. Each chunk is dereferenced once, here: Cap'n
// Proto charges a list's whole size to the traversal limit every time its
// pointer is followed, so a second pass through `chunks[i]` would count the
// array twice.
template <typename T>
std::vector<typename capnp::List<T>::Reader> readChunks(typename capnp::List<capnp::List<T>>::Reader chunks) {
  std::vector<typename capnp::List<T>::Reader> readers;
  readers.reserve(chunks.size());
  for (auto chunk : chunks) readers.push_back(chunk);
  return readers;
}

// Returns a pointer to `expectedValues` values of the chunked array: into
// the mapping when there is a single, natively encoded chunk, else into
// `joined`. Every chunk must hold whole groups (vertices, triangles).
template <typename T>
const T* gatherChunks(const std::vector<typename capnp::List<T>::Reader>& chunks, uint64_t expectedValues,
                      size_t groupSize, std::vector<T>& joined, const char* what) {
  uint64_t total = 0;
  for (size_t i = 0; i < chunks.size(); ++i) {
    const uint32_t size = chunks[i].size();
    if (size % groupSize != 0)
      throw malformed(fmt::format("{} chunk {} holds {} values, not a multiple of {}", what, i, size, groupSize));
    total += size;
  }
  if (total != expectedValues)
    throw malformed(fmt::format("{} chunks hold {} values, the header promises {}", what, total, expectedValues));
  if (total == 0) return nullptr;

  // Cap'n Proto may legally encode a primitive list with a wider element
  // (e.g. as a struct list); only the native 4-byte encoding can be used raw.
  const auto isNative = [](capnp::AnyList::Reader list) {
    return list.getElementSize() == capnp::ElementSize::FOUR_BYTES;
  };
  if (chunks.size() == 1 && isNative(chunks[0]))
    return reinterpret_cast<const T*>(capnp::AnyList::Reader(chunks[0]).getRawBytes().begin());

  joined.reserve(total);
  for (const auto& chunk : chunks) {
    if (isNative(chunk)) {
      const auto bytes = capnp::AnyList::Reader(chunk).getRawBytes();
      const T* first = reinterpret_cast<const T*>(bytes.begin());
      joined.insert(joined.end(), first, first + chunk.size());
    } else {
      for (T value : chunk) joined.push_back(value);
    }
  }
  return joined.data();
}

Vec3 readVec3(capnp::List<float>::Reader list, const char* what) {
  if (list.size() != 3) throw malformed(fmt::format("{} has {} values, expected 3", what, list.size()));
  return {list[0], list[1], list[2]};
}

}  // namespace

std::unique_ptr<CellGeometry> CellGeometry::load(const std::string& path, uint32_t expectedCellId,
                                                 size_t materialCount) {
  const auto failure = [&](const std::string& problem) {
    return std::runtime_error(fmt::format("cell file {}: {}", path, problem));
  };
  // O_NONBLOCK: a FIFO (or a device) put in a cell's place would block
  // open() for good, holding the worker's lease while its heartbeats go on;
  // it is refused below instead. A regular file ignores the flag.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw failure(fmt::format("cannot open: {}", std::strerror(errno)));
  struct stat info {};
  if (::fstat(fd, &info) != 0) {
    const int error = errno;
    ::close(fd);
    throw failure(fmt::format("cannot stat: {}", std::strerror(error)));
  }
  if (!S_ISREG(info.st_mode)) {
    ::close(fd);
    throw failure(S_ISFIFO(info.st_mode) ? "not a regular file (a FIFO)" : "not a regular file");
  }
  const auto bytes = static_cast<size_t>(info.st_size);
  if (bytes == 0 || bytes % sizeof(capnp::word) != 0) {
    ::close(fd);
    throw failure(fmt::format("size {} bytes is not a positive multiple of 8: truncated, or not a cell file", bytes));
  }
  void* mapped = ::mmap(nullptr, bytes, PROT_READ, MAP_PRIVATE, fd, 0);
  const int mapError = errno;
  ::close(fd);   // the mapping keeps the file's pages reachable
  if (mapped == MAP_FAILED) throw failure(fmt::format("cannot mmap {} bytes: {}", bytes, std::strerror(mapError)));

  std::unique_ptr<CellGeometry> cell(new CellGeometry());
  cell->mapped_ = mapped;   // from here the destructor unmaps, also on a throw below
  cell->mappedBytes_ = bytes;
  try {
    cell->readMapped(expectedCellId, materialCount);
  } catch (const kj::Exception& e) {
    throw failure(fmt::format("malformed message: {}", e.getDescription().cStr()));
  } catch (const std::runtime_error& e) {
    throw failure(e.what());
  }
  return cell;
}

CellGeometry::~CellGeometry() {
  if (mapped_) ::munmap(mapped_, mappedBytes_);
}

bool CellGeometry::readInPlace() const {
  return joinedPositions_.empty() && joinedIndices_.empty() && joinedMaterials_.empty() && joinedUvs_.empty();
}

Uv CellGeometry::uvAt(uint32_t primitive, float b1, float b2) const {
  if (!uvs_) return {0.0f, 0.0f};
  const uint32_t* corners = mesh_.indices + 3 * size_t{primitive};
  const float* a = uvs_ + 2 * size_t{corners[0]};
  const float* b = uvs_ + 2 * size_t{corners[1]};
  const float* c = uvs_ + 2 * size_t{corners[2]};
  const float b0 = 1.0f - b1 - b2;
  return {b0 * a[0] + b1 * b[0] + b2 * c[0], b0 * a[1] + b1 * b[1] + b2 * c[1]};
}

void CellGeometry::readMapped(uint32_t expectedCellId, size_t materialCount) {
  const kj::ArrayPtr<const capnp::word> words(static_cast<const capnp::word*>(mapped_),
                                              mappedBytes_ / sizeof(capnp::word));
  // The file is local and its size known: a legitimate message reads each
  // word about once, so twice its size bounds a well-formed one.
  capnp::ReaderOptions options;
  options.traversalLimitInWords = words.size() * 2 + 1024;
  capnp::FlatArrayMessageReader message(words, options);
  const auto file = message.getRoot<proto::CellFile>();

  if (file.getFormatVersion() != proto::CELL_FORMAT_VERSION)
    throw malformed(fmt::format("cell format version {}, this build reads version {}; regenerate the store",
                                file.getFormatVersion(), proto::CELL_FORMAT_VERSION));
  if (file.getCellId() != expectedCellId)
    throw malformed(fmt::format("holds cell {}, expected cell {}", file.getCellId(), expectedCellId));
  id_ = file.getCellId();
  bounds_ = Bounds3(readVec3(file.getBoundsMin(), "boundsMin"), readVec3(file.getBoundsMax(), "boundsMax"));
  if (!isFinite(bounds_.lo) || !isFinite(bounds_.hi) || bounds_.empty())
    throw malformed("bounds are not a finite, non-empty box");

  const uint64_t vertexCount = file.getVertexCount();
  const uint64_t triangleCount = file.getTriangleCount();
  const auto positionChunks = readChunks<float>(file.getPositionChunks());
  const auto indexChunks = readChunks<uint32_t>(file.getIndexChunks());
  const auto materialChunks = readChunks<uint32_t>(file.getMaterialChunks());
  // Material chunks run alongside index chunks: one id per triangle of the chunk.
  if (materialChunks.size() != indexChunks.size())
    throw malformed(fmt::format("{} material chunks for {} index chunks", materialChunks.size(), indexChunks.size()));
  for (size_t i = 0; i < indexChunks.size(); ++i)
    if (uint64_t{materialChunks[i].size()} * 3 != indexChunks[i].size())
      throw malformed(fmt::format("material chunk {} has {} ids for {} indices", i, materialChunks[i].size(),
                                  indexChunks[i].size()));

  mesh_.positions = gatherChunks<float>(positionChunks, vertexCount * 3, 3, joinedPositions_, "position");
  mesh_.vertexCount = vertexCount;
  // Positions read in place end inside the mapping (more lists follow them
  // in the file): tell Embree how far it may read past the last vertex.
  if (joinedPositions_.empty() && vertexCount > 0) {
    const char* end = reinterpret_cast<const char*>(mesh_.positions + vertexCount * 3);
    const char* mappingEnd = static_cast<const char*>(mapped_) + mappedBytes_;
    if (end >= static_cast<const char*>(mapped_) && end <= mappingEnd)
      mesh_.positionsPaddingFloats = static_cast<size_t>(mappingEnd - end) / sizeof(float);
  }
  mesh_.indices = gatherChunks<uint32_t>(indexChunks, triangleCount * 3, 3, joinedIndices_, "index");
  mesh_.triangleCount = triangleCount;
  materials_ = gatherChunks<uint32_t>(materialChunks, triangleCount, 1, joinedMaterials_, "material");

  if (file.hasUvChunks() && file.getUvChunks().size() > 0) {
    const auto uvChunks = readChunks<float>(file.getUvChunks());
    uvs_ = gatherChunks<float>(uvChunks, vertexCount * 2, 2, joinedUvs_, "uv");
    for (uint64_t i = 0; i < 2 * vertexCount; ++i)
      if (!std::isfinite(uvs_[i])) throw malformed(fmt::format("vertex {}'s uv is not finite", i / 2));
  }

  for (uint64_t v = 0; v < vertexCount; ++v) {
    const float* p = mesh_.positions + 3 * v;
    if (!isFinite(Vec3(p[0], p[1], p[2]))) throw malformed(fmt::format("vertex {} is not finite", v));
  }
  for (uint64_t i = 0; i < 3 * triangleCount; ++i)
    if (mesh_.indices[i] >= vertexCount)
      throw malformed(fmt::format("triangle {} uses vertex {}, but the cell has {} vertices", i / 3, mesh_.indices[i],
                                  vertexCount));
  for (uint64_t t = 0; t < triangleCount; ++t)
    if (materials_[t] >= materialCount)
      throw malformed(fmt::format("triangle {} uses material {}, but the store has {} materials", t, materials_[t],
                                  materialCount));

  const auto portals = file.getPortals();
  portals_.reserve(portals.size());
  for (uint32_t i = 0; i < portals.size(); ++i) {
    const auto entry = portals[i];
    const auto polygon = entry.getPolygon();
    if (polygon.size() < 9 || polygon.size() % 3 != 0)
      throw malformed(fmt::format("portal entry {} has {} polygon values, not 3 or more xyz vertices", i,
                                  polygon.size()));
    CellPortalView view;
    view.portalId = entry.getPortalId();
    view.neighborCell = entry.getNeighborCell();
    for (uint32_t v = 0; v < polygon.size(); v += 3) {
      view.polygon.emplace_back(polygon[v], polygon[v + 1], polygon[v + 2]);
      if (!isFinite(view.polygon.back())) throw malformed(fmt::format("portal {} has a non-finite vertex", view.portalId));
    }
    portals_.push_back(std::move(view));
  }
}

}  // namespace portico
