// One cell loaded for tracing: the cell file mmap'd and read in place.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common/mesh_view.h"
#include "common/scene/store/scene_types.h"

namespace portico {

// A texture coordinate: (0, 0) the image's bottom-left corner, (1, 1) its top right.
struct Uv {
  float u = 0.0f, v = 0.0f;
};

struct CellPortalView {
  uint32_t portalId = 0;
  uint32_t neighborCell = 0;
  std::vector<Vec3> polygon;
};

class CellGeometry {
 public:
  // Maps and validates the file (format version, cell id, index ranges,
  // material ids < materialCount, finite positions). Throws
  // std::runtime_error naming the file and the problem.
  static std::unique_ptr<CellGeometry> load(const std::string& path, uint32_t expectedCellId,
                                            size_t materialCount);
  ~CellGeometry();

  uint32_t id() const { return id_; }
  const Bounds3& bounds() const { return bounds_; }
  const MeshView& mesh() const { return mesh_; }
  uint32_t material(uint32_t primitive) const { return materials_[primitive]; }
  // Texture coordinates (uv per vertex), or null when the cell has none.
  const float* uvs() const { return uvs_; }
  // The uv at barycentric (b1, b2) of `primitive` (weights 1 - b1 - b2, b1,
  // b2 for its corners 0, 1, 2); (0, 0) when the cell has no uvs.
  Uv uvAt(uint32_t primitive, float b1, float b2) const;
  const std::vector<CellPortalView>& portals() const { return portals_; }
  uint64_t bytes() const { return mappedBytes_; }
  // Whether positions, indices and material ids are used where they lie in
  // the mapping (true when each was stored as one chunk): no copy was made.
  bool readInPlace() const;

 private:
  CellGeometry() = default;
  CellGeometry(const CellGeometry&) = delete;
  CellGeometry& operator=(const CellGeometry&) = delete;
  // Reads and validates the mapped message; throws kj::Exception or
  // std::runtime_error (load() adds the path).
  void readMapped(uint32_t expectedCellId, size_t materialCount);
  uint32_t id_ = 0;
  Bounds3 bounds_;
  MeshView mesh_;
  const uint32_t* materials_ = nullptr;
  const float* uvs_ = nullptr;
  std::vector<CellPortalView> portals_;
  // Storage: the mapping, plus copies only when a bulk array spans chunks.
  void* mapped_ = nullptr;
  size_t mappedBytes_ = 0;
  std::vector<float> joinedPositions_;
  std::vector<uint32_t> joinedIndices_;
  std::vector<uint32_t> joinedMaterials_;
  std::vector<float> joinedUvs_;
};

}  // namespace portico
