// SceneStoreWriter: cells stream into a staging directory beside the target
// (`<dir>.tmp-<pid>`); commit() validates the cross references, writes the
// catalogue (scene.db) in one transaction and renames the staging directory
// into place, so a reader never sees a half-written store.
#include <fmt/format.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <system_error>
#include <unordered_map>

#include "common/image/image_formats_loader.h"
#include "common/image/texture_module.h"
#include "common/scene/store/cell_file_writer.h"
#include "common/scene/store/portal_geometry.h"
#include "common/scene/store/scene_store.h"
#include "common/scene/store/scene_store_schema.h"
#include "common/util/sqlite.h"
#include "proto/scene.capnp.h"

namespace portico {

namespace fs = std::filesystem;

namespace {

std::string formatVec(const Vec3& v) { return fmt::format("({}, {}, {})", v.x, v.y, v.z); }

// A directory we may replace: an empty one, or an earlier scene store. Any
// other existing path is somebody's data.
bool isReplaceable(const fs::path& directory) {
  std::error_code error;
  if (!fs::exists(directory, error)) return true;
  if (!fs::is_directory(directory, error)) return false;
  return fs::is_empty(directory, error) || fs::exists(directory / scene_schema::kDatabaseFile, error);
}

// Whether `p` lies in `box` grown by boxTolerance (coordinates computed by
// an importer or generator may be a few ulps off).
bool nearlyContains(const Bounds3& box, const Vec3& p) {
  const float tolerance = boxTolerance(box);
  return box.contains(p) || Bounds3(box.lo - Vec3(tolerance), box.hi + Vec3(tolerance)).contains(p);
}

}  // namespace

struct SceneStoreWriter::Impl {
  // What commit() needs to know about a cell already on disk.
  struct WrittenCell {
    CellInfo info;
    std::optional<uint32_t> largestMaterial;   // none for a cell without triangles
    size_t triangleWithLargestMaterial = 0;
  };

  fs::path target;
  fs::path staging;
  bool committed = false;
  uint64_t maxChunkElements = kMaxCellChunkElements;
  std::vector<Material> materials;
  std::vector<Portal> portals;
  // Portal ids by cell, filled by addPortal: writeCell looks up its portals
  // instead of scanning them all (an RG^3 voxel grid has 3 RG^2 (RG - 1)).
  std::unordered_map<uint32_t, std::vector<uint32_t>> portalsByCell;
  std::vector<AreaLight> lights;
  std::optional<Camera> camera;          // the default
  std::vector<Camera> otherCameras;      // the other named cameras, in order
  std::map<std::string, std::string> meta;
  std::optional<SiteLocation> site;
  std::map<uint32_t, WrittenCell> cells;

  [[noreturn]] void fail(const std::string& problem) const {
    throw std::runtime_error(fmt::format("scene store {}: {}", target.string(), problem));
  }
  void requireUncommitted() const {
    if (committed) fail("already committed; a SceneStoreWriter writes one store");
  }
  std::string describeCell(uint32_t id) const {
    auto it = cells.find(id);
    return it == cells.end() ? fmt::format("cell {}", id) : fmt::format("cell {} ('{}')", id, it->second.info.name);
  }

  void checkCamera(const Camera& camera) const;
  void validateCameras() const;
  void validateCrossReferences() const;
  void writeCatalogue(const fs::path& databasePath) const;
  void publish();
};

SceneStoreWriter::SceneStoreWriter(std::string directory) : impl_(new Impl) {
  if (directory.empty()) {
    delete impl_;
    throw std::runtime_error("scene store: empty directory name");
  }
  fs::path target = fs::path(directory).lexically_normal();
  if (!target.has_filename()) target = target.parent_path();   // "store/" names "store"
  impl_->target = target;
  impl_->staging = fs::path(target.string() + fmt::format(".tmp-{}", ::getpid()));
  impl_->meta = {{"format", "portico-scene-store"},
                 {"format_version", std::to_string(scene_schema::kVersion)},
                 {"cell_format_version", std::to_string(proto::CELL_FORMAT_VERSION)},
                 {"generator", "portico"}};
  try {
    // Fail before any work is done rather than after an hour of import.
    if (!isReplaceable(target)) impl_->fail("exists and is not a scene store; refusing to replace it");
    if (target.has_parent_path()) fs::create_directories(target.parent_path());
    fs::remove_all(impl_->staging);   // left by a crashed run that had our pid
    fs::create_directories(impl_->staging / scene_schema::kCellDirectory);
  } catch (const fs::filesystem_error& e) {
    const std::string message = fmt::format("scene store {}: cannot create staging directory: {}", target.string(),
                                            e.what());
    delete impl_;
    throw std::runtime_error(message);
  } catch (...) {
    delete impl_;
    throw;
  }
}

SceneStoreWriter::~SceneStoreWriter() {
  if (!impl_->committed) {
    std::error_code ignored;   // destructors must not throw; a leftover is harmless
    fs::remove_all(impl_->staging, ignored);
  }
  delete impl_;
}

void SceneStoreWriter::setMaxChunkElements(uint64_t elements) {
  if (elements < 3 || elements > kMaxCellChunkElements)
    impl_->fail(fmt::format("chunk size {} is outside [3, {}]", elements, kMaxCellChunkElements));
  impl_->maxChunkElements = elements;
}

uint32_t SceneStoreWriter::addMaterial(const std::string& name, const Vec3& albedo, const Vec3& emission,
                                       bool hiddenFromCamera) {
  impl_->requireUncommitted();
  const auto id = static_cast<uint32_t>(impl_->materials.size());
  const std::string what = fmt::format("material {} ('{}')", id, name);
  if (!isFinite(albedo) || std::min({albedo.x, albedo.y, albedo.z}) < 0.0f || maxComponent(albedo) > 1.0f)
    impl_->fail(fmt::format("{}: albedo {} must be finite and within [0, 1]", what, formatVec(albedo)));
  if (!isFinite(emission) || std::min({emission.x, emission.y, emission.z}) < 0.0f)
    impl_->fail(fmt::format("{}: emission {} must be finite and non-negative", what, formatVec(emission)));
  Material material{id, name, albedo, emission};
  material.hiddenFromCamera = hiddenFromCamera;
  impl_->materials.push_back(std::move(material));
  return id;
}

void SceneStoreWriter::setMaterialGlass(uint32_t id, const Vec3& transmittance, float ior) {
  impl_->requireUncommitted();
  if (id >= impl_->materials.size()) impl_->fail(fmt::format("glass for material {}, which was not added", id));
  const std::string what = fmt::format("material {} ('{}')", id, impl_->materials[id].name);
  if (!isFinite(transmittance) || std::min({transmittance.x, transmittance.y, transmittance.z}) < 0.0f ||
      maxComponent(transmittance) > 1.0f || !(maxComponent(transmittance) > 0.0f))
    impl_->fail(fmt::format("{}: glass transmittance {} must be finite, within [0, 1] and not all 0", what,
                            formatVec(transmittance)));
  if (!(ior >= 1.0f && ior <= 4.0f)) impl_->fail(fmt::format("{}: glass ior {} must be from 1 to 4", what, ior));
  impl_->materials[id].transmittance = transmittance;
  impl_->materials[id].ior = ior;
}

uint32_t SceneStoreWriter::addPortal(uint32_t cellA, uint32_t cellB, const std::vector<Vec3>& polygon) {
  impl_->requireUncommitted();
  const auto id = static_cast<uint32_t>(impl_->portals.size());
  const std::string what = fmt::format("portal {} (cells {} and {})", id, cellA, cellB);
  if (cellA == cellB) impl_->fail(fmt::format("{}: joins a cell to itself", what));
  for (uint32_t cell : {cellA, cellB})
    if (impl_->cells.count(cell))
      impl_->fail(fmt::format("{}: {} was already written; add portals before writing the cells they touch",
                              what, impl_->describeCell(cell)));
  if (std::string problem = portalShapeProblem(polygon); !problem.empty())
    impl_->fail(fmt::format("{}: polygon {}", what, problem));
  impl_->portals.push_back(Portal{id, cellA, cellB, polygon});
  impl_->portalsByCell[cellA].push_back(id);
  impl_->portalsByCell[cellB].push_back(id);
  return id;
}

uint32_t SceneStoreWriter::addLight(const AreaLight& light) {
  impl_->requireUncommitted();
  AreaLight stored = light;
  stored.id = static_cast<uint32_t>(impl_->lights.size());
  const std::string what = fmt::format("light {} (cell {})", stored.id, stored.cell);
  if (!isFinite(light.corner) || !isFinite(light.edge1) || !isFinite(light.edge2))
    impl_->fail(fmt::format("{}: corner or edges are not finite", what));
  if (light.isPoint()) {
    if (!light.intensity || !(light.intensity->lumens() > 0))
      impl_->fail(fmt::format("{}: a point luminaire needs a candela distribution that emits", what));
    if (std::abs(length(light.edge1) - 1.0f) > 1e-4f || std::abs(length(light.edge2) - 1.0f) > 1e-4f ||
        std::abs(dot(light.edge1, light.edge2)) > 1e-4f)
      impl_->fail(fmt::format("{}: its nadir {} and C0 direction {} must be perpendicular unit vectors", what,
                              formatVec(light.edge1), formatVec(light.edge2)));
  } else if (!(light.area() > 0.0f)) {
    impl_->fail(fmt::format("{}: has zero area (edges are parallel or zero)", what));
  }
  if (!isFinite(light.radiance) || std::min({light.radiance.x, light.radiance.y, light.radiance.z}) < 0.0f)
    impl_->fail(fmt::format("{}: radiance {} must be finite and non-negative", what, formatVec(light.radiance)));
  impl_->lights.push_back(stored);
  return stored.id;
}

void SceneStoreWriter::setCamera(const Camera& camera) {
  impl_->requireUncommitted();
  Camera named = camera;
  if (named.name.empty()) named.name = kDefaultCameraName;
  impl_->checkCamera(named);
  impl_->camera = std::move(named);
}

void SceneStoreWriter::addCamera(const Camera& camera) {
  impl_->requireUncommitted();
  impl_->checkCamera(camera);
  impl_->otherCameras.push_back(camera);
}

void SceneStoreWriter::setMaterialTexture(uint32_t material, const std::string& sourceImage) {
  impl_->requireUncommitted();
  if (material >= impl_->materials.size())
    impl_->fail(fmt::format("texture {}: no material {} (there are {})", sourceImage, material,
                            impl_->materials.size()));
  Material& target = impl_->materials[material];
  const std::string file = fmt::format("{}/{}.tif", scene_schema::kTextureDirectory, material);
  std::error_code ignored;
  fs::create_directories(impl_->staging / scene_schema::kTextureDirectory, ignored);
  const auto convert = reinterpret_cast<PorticoTextureConvertFn>(imageFormatsEntry(kTextureConvertEntry));
  char error[512] = "";
  if (convert(sourceImage.c_str(), (impl_->staging / file).c_str(), error, sizeof error) != 0)
    impl_->fail(fmt::format("material '{}': texture {}: {}", target.name, sourceImage, error));
  target.albedoTexture = file;
}

void SceneStoreWriter::setMeta(const std::string& key, const std::string& value) {
  impl_->requireUncommitted();
  impl_->meta[key] = value;
}

void SceneStoreWriter::setSite(const SiteLocation& site) {
  impl_->requireUncommitted();
  if (const std::string problem = siteLocationProblem(site); !problem.empty()) impl_->fail("site: " + problem);
  impl_->site = site;
}

void SceneStoreWriter::writeCell(const CellContent& cell) {
  impl_->requireUncommitted();
  const std::string what = fmt::format("cell {} ('{}')", cell.id, cell.name);
  if (impl_->cells.count(cell.id)) impl_->fail(fmt::format("{}: written twice", what));
  if (!isFinite(cell.bounds.lo) || !isFinite(cell.bounds.hi) || cell.bounds.empty())
    impl_->fail(fmt::format("{}: bounds {} - {} are not a finite, non-empty box", what, formatVec(cell.bounds.lo),
                            formatVec(cell.bounds.hi)));
  if (cell.positions.size() % 3 != 0)
    impl_->fail(fmt::format("{}: {} position values is not a whole number of xyz vertices", what,
                            cell.positions.size()));
  if (cell.indices.size() % 3 != 0)
    impl_->fail(fmt::format("{}: {} indices is not a whole number of triangles", what, cell.indices.size()));
  const size_t vertexCount = cell.positions.size() / 3;
  const size_t triangleCount = cell.indices.size() / 3;
  if (cell.materials.size() != triangleCount)
    impl_->fail(fmt::format("{}: {} material ids for {} triangles", what, cell.materials.size(), triangleCount));
  if (!cell.uvs.empty() && cell.uvs.size() != 2 * vertexCount)
    impl_->fail(fmt::format("{}: {} uv values for {} vertices (2 per vertex, or none)", what, cell.uvs.size(),
                            vertexCount));
  for (size_t i = 0; i < cell.uvs.size(); ++i)
    if (!std::isfinite(cell.uvs[i])) impl_->fail(fmt::format("{}: vertex {}'s uv is not finite", what, i / 2));
  if (vertexCount > UINT32_MAX)
    impl_->fail(fmt::format("{}: {} vertices do not fit 32-bit indices; split the cell", what, vertexCount));

  for (size_t v = 0; v < vertexCount; ++v) {
    const Vec3 p(cell.positions[3 * v], cell.positions[3 * v + 1], cell.positions[3 * v + 2]);
    if (!isFinite(p)) impl_->fail(fmt::format("{}: vertex {} is not finite {}", what, v, formatVec(p)));
  }
  Impl::WrittenCell written;
  for (size_t t = 0; t < triangleCount; ++t) {
    for (int corner = 0; corner < 3; ++corner)
      if (cell.indices[3 * t + corner] >= vertexCount)
        impl_->fail(fmt::format("{}: triangle {} uses vertex {} but the cell has {} vertices", what, t,
                                cell.indices[3 * t + corner], vertexCount));
    if (!written.largestMaterial || cell.materials[t] > *written.largestMaterial) {
      written.largestMaterial = cell.materials[t];
      written.triangleWithLargestMaterial = t;
    }
  }

  std::vector<const Portal*> touching;
  if (auto it = impl_->portalsByCell.find(cell.id); it != impl_->portalsByCell.end())
    for (uint32_t portal : it->second) touching.push_back(&impl_->portals[portal]);   // in id order, as before

  const std::string file = fmt::format("{}/{}.cell", scene_schema::kCellDirectory, cell.id);
  written.info = CellInfo{cell.id, cell.name, cell.bounds, triangleCount, 0, file};
  written.info.byteCount = writeCellFile((impl_->staging / file).string(), cell, touching, impl_->maxChunkElements);
  impl_->cells.emplace(cell.id, std::move(written));
}

// Names are what `--camera NAME` takes: printable, no control characters.
void SceneStoreWriter::Impl::checkCamera(const Camera& camera) const {
  if (camera.name.empty()) fail("camera: a camera other than the default needs a name");
  if (camera.name.size() > kMaxCameraNameBytes)
    fail(fmt::format("camera '{}...': name longer than {} bytes", camera.name.substr(0, 32), kMaxCameraNameBytes));
  for (const char c : camera.name)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
      fail(fmt::format("camera '{}': name holds a control character", camera.name));
  const std::string what = fmt::format("camera '{}'", camera.name);
  if (!isFinite(camera.origin) || !isFinite(camera.target) || !isFinite(camera.up))
    fail(fmt::format("{}: origin, target or up is not finite", what));
  if (camera.origin == camera.target) fail(fmt::format("{}: origin and target coincide", what));
  if (length(cross(camera.target - camera.origin, camera.up)) == 0.0f)
    fail(fmt::format("{}: up is parallel to the view direction", what));
  if (!(camera.fovYDegrees > 0.0f && camera.fovYDegrees < 180.0f))
    fail(fmt::format("{}: field of view {} degrees is outside (0, 180)", what, camera.fovYDegrees));
  if (camera.width == 0 || camera.height == 0)
    fail(fmt::format("{}: image size {}x{} is empty", what, camera.width, camera.height));
}

// Every camera's eye lies in its cell; names are unique.
void SceneStoreWriter::Impl::validateCameras() const {
  if (!camera) fail("no camera was set (call setCamera before commit)");
  std::set<std::string_view> names;
  std::vector<const Camera*> all{&*camera};
  for (const Camera& other : otherCameras) all.push_back(&other);
  for (const Camera* each : all) {
    if (!names.insert(each->name).second) fail(fmt::format("camera '{}': the name is used twice", each->name));
    auto it = cells.find(each->cell);
    if (it == cells.end()) fail(fmt::format("camera '{}': its cell {} was never written", each->name, each->cell));
    if (!nearlyContains(it->second.info.bounds, each->origin))
      fail(fmt::format("camera '{}': origin {} lies outside the bounds of its {}", each->name,
                       formatVec(each->origin), describeCell(each->cell)));
  }
}

void SceneStoreWriter::Impl::validateCrossReferences() const {
  if (cells.empty()) fail("no cells were written");
  // Ids are dense: std::map iterates in order, so the first gap is the first mismatch.
  uint32_t expected = 0;
  for (const auto& [id, cell] : cells) {
    if (id != expected)
      fail(fmt::format("cell {} was never written (cell ids must run from 0 without gaps; {} was written)",
                       expected, id));
    ++expected;
  }
  for (const Portal& portal : portals)
    for (uint32_t cell : {portal.cellA, portal.cellB})
      if (!cells.count(cell))
        fail(fmt::format("portal {} (cells {} and {}): cell {} was never written", portal.id, portal.cellA,
                         portal.cellB, cell));
  for (const auto& [id, cell] : cells)
    if (cell.largestMaterial && *cell.largestMaterial >= materials.size())
      fail(fmt::format("{}: triangle {} uses material {} but only {} materials were added", describeCell(id),
                       cell.triangleWithLargestMaterial, *cell.largestMaterial, materials.size()));
  for (const AreaLight& light : lights) {
    auto it = cells.find(light.cell);
    if (it == cells.end()) fail(fmt::format("light {}: its cell {} was never written", light.id, light.cell));
    if (!nearlyContains(it->second.info.bounds, light.center()))
      fail(fmt::format("light {}: its centre {} lies outside the bounds of {}", light.id, formatVec(light.center()),
                       describeCell(light.cell)));
  }
  validateCameras();
}

void SceneStoreWriter::Impl::writeCatalogue(const fs::path& databasePath) const {
  sql::Database db(databasePath.string(), sql::Database::Mode::ReadWriteCreate);
  sql::Transaction transaction(db);
  db.exec(scene_schema::kCreateTables);
  db.setUserVersion(scene_schema::kVersion);

  for (const auto& [key, value] : meta) db.prepare("INSERT INTO meta VALUES (?, ?)").bind(1, key).bind(2, value).run();
  for (const auto& [id, cell] : cells) {
    const CellInfo& info = cell.info;
    sql::Statement& insert = db.prepare("INSERT INTO cells VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    insert.bind(1, int64_t{info.id}).bind(2, info.name);
    for (int axis = 0; axis < 3; ++axis) {
      insert.bind(3 + axis, double{info.bounds.lo[axis]});
      insert.bind(6 + axis, double{info.bounds.hi[axis]});
    }
    insert.bind(9, static_cast<int64_t>(info.triangleCount)).bind(10, static_cast<int64_t>(info.byteCount));
    insert.bind(11, info.file).run();
  }
  for (const Portal& portal : portals) {
    std::vector<float> polygon;
    for (const Vec3& v : portal.polygon) polygon.insert(polygon.end(), {v.x, v.y, v.z});
    db.prepare("INSERT INTO portals VALUES (?, ?, ?, ?)")
        .bind(1, int64_t{portal.id})
        .bind(2, int64_t{portal.cellA})
        .bind(3, int64_t{portal.cellB})
        .bindBlob(4, polygon.data(), polygon.size() * sizeof(float))
        .run();
  }
  for (const Material& material : materials) {
    sql::Statement& insert = db.prepare("INSERT INTO materials VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    insert.bind(1, int64_t{material.id}).bind(2, material.name);
    for (int c = 0; c < 3; ++c) {
      insert.bind(3 + c, double{material.albedo[c]});
      insert.bind(6 + c, double{material.emission[c]});
    }
    insert.bind(9, int64_t{material.hiddenFromCamera ? 1 : 0});
    for (int c = 0; c < 3; ++c) insert.bind(10 + c, double{material.transmittance[c]});
    insert.bind(13, double{material.ior});
    insert.run();
    if (material.textured())
      db.prepare("INSERT INTO material_textures VALUES (?, ?)")
          .bind(1, int64_t{material.id})
          .bind(2, material.albedoTexture)
          .run();
  }
  for (const AreaLight& light : lights) {
    sql::Statement& insert = db.prepare("INSERT INTO lights VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    insert.bind(1, int64_t{light.id}).bind(2, int64_t{light.cell});
    for (int c = 0; c < 3; ++c) {
      insert.bind(3 + c, double{light.corner[c]});
      insert.bind(6 + c, double{light.edge1[c]});
      insert.bind(9 + c, double{light.edge2[c]});
      insert.bind(12 + c, double{light.radiance[c]});
    }
    insert.bind(15, std::string(light.isPoint() ? "point" : light.isTriangle() ? "triangle" : "parallelogram"));
    insert.run();
  }
  // Point luminaires: each distinct candela distribution once.
  std::map<const LuminousIntensity*, int64_t> distributions;
  for (const AreaLight& light : lights) {
    if (!light.isPoint()) continue;
    auto [it, fresh] = distributions.emplace(light.intensity.get(), int64_t(distributions.size()));
    if (fresh) {
      const CandelaGrid& grid = light.intensity->grid();
      db.prepare("INSERT INTO light_distributions VALUES (?, ?, ?, ?, ?)")
          .bind(1, it->second)
          .bind(2, light.intensity->name())
          .bindBlob(3, grid.vertical.data(), grid.vertical.size() * sizeof(double))
          .bindBlob(4, grid.horizontal.data(), grid.horizontal.size() * sizeof(double))
          .bindBlob(5, grid.candela.data(), grid.candela.size() * sizeof(double))
          .run();
    }
    db.prepare("INSERT INTO point_lights VALUES (?, ?, ?, ?, ?)")
        .bind(1, int64_t{light.id})
        .bind(2, it->second)
        .bind(3, light.opening.width())
        .bind(4, light.opening.length())
        .bind(5, light.opening.height())
        .run();
  }
  int64_t cameraId = 0;
  const auto insertCamera = [&](const Camera& c) {
    sql::Statement& insert = db.prepare("INSERT INTO cameras VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    insert.bind(1, cameraId++).bind(2, c.name);
    for (int k = 0; k < 3; ++k) {
      insert.bind(3 + k, double{c.origin[k]});
      insert.bind(6 + k, double{c.target[k]});
      insert.bind(9 + k, double{c.up[k]});
    }
    insert.bind(12, double{c.fovYDegrees})
        .bind(13, int64_t{c.width})
        .bind(14, int64_t{c.height})
        .bind(15, int64_t{c.cell})
        .run();
  };
  insertCamera(*camera);
  for (const Camera& other : otherCameras) insertCamera(other);
  if (site)
    db.prepare("INSERT INTO site VALUES (0, ?, ?, ?)")
        .bind(1, site->latitudeDegrees)
        .bind(2, site->longitudeDegrees)
        .bind(3, site->northAzimuthDegrees)
        .run();
  transaction.commit();
}

void SceneStoreWriter::Impl::publish() {
  if (!isReplaceable(target)) fail("exists and is not a scene store; refusing to replace it");
  try {
    if (!fs::exists(target)) {
      fs::rename(staging, target);
      return;
    }
    // Move the old store aside first: rename cannot replace a non-empty
    // directory, and this keeps the window without a store to one rename.
    const fs::path old(target.string() + fmt::format(".old-{}", ::getpid()));
    fs::remove_all(old);
    fs::rename(target, old);
    fs::rename(staging, target);
    fs::remove_all(old);
  } catch (const fs::filesystem_error& e) {
    fail(fmt::format("cannot move the finished store into place: {}", e.what()));
  }
}

void SceneStoreWriter::commit() {
  impl_->requireUncommitted();
  impl_->validateCrossReferences();
  try {
    impl_->writeCatalogue(impl_->staging / scene_schema::kDatabaseFile);
  } catch (const std::runtime_error& e) {
    impl_->fail(fmt::format("cannot write the catalogue: {}", e.what()));
  }
  impl_->publish();
  impl_->committed = true;
}

}  // namespace portico
