// A scene store on disk: a directory holding scene.db (the catalogue, SQLite)
// and one unpacked Cap'n Proto file per cell under cells/.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "common/scene/store/scene_types.h"
#include "common/scene/store/site_location.h"

namespace portico {

// Read side: the catalogue, loaded whole (it is small: no triangles in it).
class SceneStore {
 public:
  // Throws std::runtime_error naming the path and the problem.
  static SceneStore open(const std::string& directory);

  const std::string& directory() const { return directory_; }
  const std::vector<CellInfo>& cells() const { return cells_; }        // indexed by cell id
  const std::vector<Portal>& portals() const { return portals_; }      // indexed by portal id
  const std::vector<Material>& materials() const { return materials_; } // indexed by material id
  const std::vector<AreaLight>& lights() const { return lights_; }     // indexed by light id
  // Every named camera, the default first (never empty).
  const std::vector<Camera>& cameras() const { return cameras_; }
  const Camera& camera() const { return cameras_.front(); }   // the default camera
  // The camera of this name; nullptr if the store has none.
  const Camera* findCamera(std::string_view name) const;
  // Where the building stands (building.json "site"); nullopt when unknown.
  const std::optional<SiteLocation>& site() const { return site_; }
  // Free-form facts about the store (format, generator, seed, ...).
  const std::map<std::string, std::string>& meta() const { return meta_; }
  std::string cellPath(uint32_t cell) const;      // absolute path of the cell file
  std::string cataloguePath() const;              // absolute path of scene.db
  // The cells a portal joins to `cell` (one entry per portal) and the
  // lights in it, indexed once at open: a lease's light sampler looks a few
  // portals around its cell, not at the whole building.
  const std::vector<uint32_t>& neighboursOf(uint32_t cell) const { return neighbours_.at(cell); }
  const std::vector<uint32_t>& lightsOf(uint32_t cell) const { return lightsByCell_.at(cell); }
  // The cell whose bounds contain p (the smallest, when several do); nullopt if none.
  std::optional<uint32_t> locateCell(const Vec3& p) const;
  uint64_t totalTriangles() const;

 private:
  std::string directory_;
  std::vector<CellInfo> cells_;
  std::vector<Portal> portals_;
  std::vector<Material> materials_;
  std::vector<AreaLight> lights_;
  std::vector<Camera> cameras_;
  std::map<std::string, std::string> meta_;
  std::optional<SiteLocation> site_;
  std::vector<std::vector<uint32_t>> neighbours_, lightsByCell_;
  void indexByCell();
};

// The geometry of one cell as written to its cell file.
struct CellContent {
  uint32_t id = 0;
  std::string name;
  Bounds3 bounds;
  std::vector<float> positions;       // xyz per vertex
  std::vector<uint32_t> indices;      // 3 per triangle
  std::vector<uint32_t> materials;    // 1 per triangle
  std::vector<float> uvs;             // uv per vertex, or empty: no textured triangle
};

// Write side. Cells stream to disk one at a time (writeCell), so a building
// larger than memory can be written. Nothing is visible at `directory` until
// commit(): the store is built in a sibling temporary directory and renamed.
class SceneStoreWriter {
 public:
  explicit SceneStoreWriter(std::string directory);
  ~SceneStoreWriter();   // removes the temporary directory if not committed
  SceneStoreWriter(const SceneStoreWriter&) = delete;
  SceneStoreWriter& operator=(const SceneStoreWriter&) = delete;

  // Bulk lists in cell files are cut into chunks of at most this many
  // elements (default and maximum 2^28 - 1; whole vertices / triangles per
  // chunk). Smaller values exist so tests can exercise multi-chunk cells.
  void setMaxChunkElements(uint64_t elements);

  // hiddenFromCamera: see Material (cut-away ceilings and their lamps).
  uint32_t addMaterial(const std::string& name, const Vec3& albedo, const Vec3& emission = Vec3(0),
                       bool hiddenFromCamera = false);
  // Gives material `material` an albedo texture: a copy of `sourceImage` (any
  // format OpenImageIO reads) as a tiled TIFF under textures/, so the store
  // is self-contained and lookups read tiles. Throws std::runtime_error
  // naming the material and the file when it cannot be read.
  void setMaterialTexture(uint32_t material, const std::string& sourceImage);
  // Makes material `id` thin glass (Material::transmittance, ior).
  void setMaterialGlass(uint32_t id, const Vec3& transmittance, float ior);
  // Portals must be added before the cells they touch are written.
  uint32_t addPortal(uint32_t cellA, uint32_t cellB, const std::vector<Vec3>& polygon);
  uint32_t addLight(const AreaLight& light);  // id assigned
  // The default camera (camera.name: "default" unless given another).
  void setCamera(const Camera& camera);
  // Another named camera; names are unique in a store (checked at commit).
  void addCamera(const Camera& camera);
  void setMeta(const std::string& key, const std::string& value);
  // Where the building stands (SiteLocation); none unless set.
  void setSite(const SiteLocation& site);
  // Writes cells/<id>.cell with its triangles and the portals that touch it.
  void writeCell(const CellContent& cell);
  // Validates (every portal's cells written, every camera's cell exists, ...) and publishes.
  // An existing directory is replaced only if it is empty or a scene store.
  // Every error is a std::runtime_error naming the object and the problem,
  // and leaves `directory` untouched.
  void commit();

 private:
  struct Impl;
  Impl* impl_;
};

}  // namespace portico
