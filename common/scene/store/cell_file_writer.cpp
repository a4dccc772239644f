#include "common/scene/store/cell_file_writer.h"

#include <capnp/any.h>
#include <capnp/message.h>
#include <capnp/serialize.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <kj/exception.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "proto/scene.capnp.h"

namespace portico {

// Cell files are read in place: the floats and integers in the file are used
// as native ones, which Cap'n Proto's little-endian encoding makes true here.
static_assert(std::endian::native == std::endian::little, "cell files are read in place: little-endian only");

namespace {

// Copies `count` values starting at `first` into a freshly initialised list.
// The list lives in our own builder's segment, so writing through its raw
// bytes is safe; Cap'n Proto has no mutable raw view of a primitive list, and
// element-by-element set() costs seconds on a cell of 10^8 triangles.
template <typename T>
void copyIntoList(typename capnp::List<T>::Builder list, const T* first, size_t count) {
  if (count == 0) return;
  const kj::ArrayPtr<const kj::byte> bytes = capnp::AnyList::Reader(list.asReader()).getRawBytes();
  std::memcpy(const_cast<kj::byte*>(bytes.begin()), first, count * sizeof(T));
}

// Fills `chunks` with `values`, `groupSize` values per whole group (vertex,
// triangle), at most `groupsPerChunk` groups per chunk.
template <typename T>
void fillChunks(typename capnp::List<capnp::List<T>>::Builder chunks, const std::vector<T>& values,
                size_t groupSize, size_t groupsPerChunk) {
  const size_t valuesPerChunk = groupSize * groupsPerChunk;
  for (uint32_t chunk = 0; chunk < chunks.size(); ++chunk) {
    const size_t first = chunk * valuesPerChunk;
    const size_t count = std::min(valuesPerChunk, values.size() - first);
    copyIntoList<T>(chunks.init(chunk, static_cast<uint32_t>(count)), values.data() + first, count);
  }
}

size_t chunkCount(size_t groups, size_t groupsPerChunk) { return (groups + groupsPerChunk - 1) / groupsPerChunk; }

void setVector(capnp::List<float>::Builder list, const Vec3& v) {
  list.set(0, v.x);
  list.set(1, v.y);
  list.set(2, v.z);
}

// A first segment large enough for the whole message, so that the file is a
// single segment (one allocation when writing, simplest layout to read).
uint32_t estimateWords(const CellContent& cell, const std::vector<const Portal*>& portals, size_t chunks) {
  const uint64_t bulkBytes =
      (cell.positions.size() + cell.indices.size() + cell.materials.size() + cell.uvs.size()) * 4;
  uint64_t words = bulkBytes / 8 + 256 + 4 * chunks;
  for (const Portal* portal : portals) words += 8 + 2 * portal->polygon.size();
  return static_cast<uint32_t>(std::min<uint64_t>(words, uint64_t{1} << 31));
}

void writeMessage(const std::string& path, capnp::MessageBuilder& message) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error(fmt::format("cell file {}: cannot create: {}", path, std::strerror(errno)));
  try {
    capnp::writeMessageToFd(fd, message);
  } catch (const kj::Exception& e) {
    ::close(fd);
    throw std::runtime_error(fmt::format("cell file {}: write failed: {}", path, e.getDescription().cStr()));
  }
  if (::close(fd) != 0)
    throw std::runtime_error(fmt::format("cell file {}: write failed: {}", path, std::strerror(errno)));
}

}  // namespace

uint64_t writeCellFile(const std::string& path, const CellContent& cell, const std::vector<const Portal*>& portals,
                       uint64_t maxChunkElements) {
  const size_t groupsPerChunk = std::max<uint64_t>(1, std::min(maxChunkElements, kMaxCellChunkElements) / 3);
  const size_t vertexCount = cell.positions.size() / 3;
  const size_t triangleCount = cell.indices.size() / 3;
  const size_t positionChunks = chunkCount(vertexCount, groupsPerChunk);
  const size_t triangleChunks = chunkCount(triangleCount, groupsPerChunk);

  const size_t uvChunks = cell.uvs.empty() ? 0 : positionChunks;
  capnp::MallocMessageBuilder message(estimateWords(cell, portals, positionChunks + 2 * triangleChunks + uvChunks));
  auto file = message.initRoot<proto::CellFile>();
  file.setFormatVersion(proto::CELL_FORMAT_VERSION);
  file.setCellId(cell.id);
  setVector(file.initBoundsMin(3), cell.bounds.lo);
  setVector(file.initBoundsMax(3), cell.bounds.hi);
  file.setVertexCount(vertexCount);
  file.setTriangleCount(triangleCount);
  fillChunks<float>(file.initPositionChunks(positionChunks), cell.positions, 3, groupsPerChunk);
  fillChunks<uint32_t>(file.initIndexChunks(triangleChunks), cell.indices, 3, groupsPerChunk);
  fillChunks<uint32_t>(file.initMaterialChunks(triangleChunks), cell.materials, 1, groupsPerChunk);
  if (!cell.uvs.empty()) fillChunks<float>(file.initUvChunks(uvChunks), cell.uvs, 2, groupsPerChunk);

  auto portalList = file.initPortals(static_cast<uint32_t>(portals.size()));
  for (uint32_t i = 0; i < portals.size(); ++i) {
    const Portal& portal = *portals[i];
    auto entry = portalList[i];
    entry.setPortalId(portal.id);
    entry.setNeighborCell(portal.cellA == cell.id ? portal.cellB : portal.cellA);
    auto polygon = entry.initPolygon(static_cast<uint32_t>(3 * portal.polygon.size()));
    for (uint32_t v = 0; v < portal.polygon.size(); ++v) {
      polygon.set(3 * v + 0, portal.polygon[v].x);
      polygon.set(3 * v + 1, portal.polygon[v].y);
      polygon.set(3 * v + 2, portal.polygon[v].z);
    }
  }

  writeMessage(path, message);
  return capnp::computeSerializedSizeInWords(message) * sizeof(capnp::word);
}

}  // namespace portico
