// SceneStore: reads a scene store's catalogue (scene.db) whole. The write
// side is in scene_store_writer.cpp, the schema in scene_store_schema.h.
#include "common/scene/store/scene_store.h"

#include <fmt/format.h>

#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "common/scene/store/scene_store_schema.h"
#include "common/util/sqlite.h"

namespace portico {

namespace fs = std::filesystem;

namespace {

// A problem with the catalogue's content, already phrased for the user;
// anything else thrown while reading is an SQLite error and gets context.
struct CatalogueError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

Vec3 columnVec3(const sql::Statement& row, int firstColumn) {
  return {static_cast<float>(row.columnDouble(firstColumn)), static_cast<float>(row.columnDouble(firstColumn + 1)),
          static_cast<float>(row.columnDouble(firstColumn + 2))};
}

class CatalogueReader {
 public:
  CatalogueReader(sql::Database& db, const fs::path& directory) : db_(db), directory_(directory) {}

  [[noreturn]] void fail(const std::string& problem) const {
    throw CatalogueError(fmt::format("scene store {}: {}", directory_.string(), problem));
  }
  // Rows are indexed by id: ids must run 0, 1, 2, ... without gaps.
  void requireDenseId(const char* table, int64_t id, size_t expected) const {
    if (id != static_cast<int64_t>(expected))
      fail(fmt::format("table {}: expected id {}, found {} (ids must be dense from 0)", table, expected, id));
  }
  void requireCell(const std::string& what, int64_t cell, size_t cellCount) const {
    if (cell < 0 || cell >= static_cast<int64_t>(cellCount))
      fail(fmt::format("{} refers to cell {}, but the store has {} cells", what, cell, cellCount));
  }

  std::map<std::string, std::string> meta() {
    std::map<std::string, std::string> meta;
    sql::Statement& row = db_.prepare("SELECT key, value FROM meta");
    while (row.step()) meta[row.columnText(0)] = row.columnText(1);
    return meta;
  }

  std::vector<CellInfo> cells() {
    std::vector<CellInfo> cells;
    sql::Statement& row = db_.prepare(
        "SELECT id, name, min_x, min_y, min_z, max_x, max_y, max_z, triangle_count, byte_count, file "
        "FROM cells ORDER BY id");
    while (row.step()) {
      requireDenseId("cells", row.columnInt(0), cells.size());
      CellInfo cell;
      cell.id = static_cast<uint32_t>(row.columnInt(0));
      cell.name = row.columnText(1);
      cell.bounds = Bounds3(columnVec3(row, 2), columnVec3(row, 5));
      cell.triangleCount = static_cast<uint64_t>(row.columnInt(8));
      cell.byteCount = static_cast<uint64_t>(row.columnInt(9));
      cell.file = row.columnText(10);
      // Its own file of the store's cells/ folder, as written: a worker
      // opens it, and one fetching stores writes it under that name.
      if (cell.file != fmt::format("{}/{}.cell", scene_schema::kCellDirectory, cell.id))
        fail(fmt::format("cell {}'s file '{}' is not {}/{}.cell", cell.id, cell.file, scene_schema::kCellDirectory,
                         cell.id));
      cells.push_back(std::move(cell));
    }
    return cells;
  }

  std::vector<Portal> portals(size_t cellCount) {
    std::vector<Portal> portals;
    sql::Statement& row = db_.prepare("SELECT id, cell_a, cell_b, polygon FROM portals ORDER BY id");
    while (row.step()) {
      requireDenseId("portals", row.columnInt(0), portals.size());
      Portal portal;
      portal.id = static_cast<uint32_t>(row.columnInt(0));
      const std::string what = fmt::format("portal {}", portal.id);
      requireCell(what, row.columnInt(1), cellCount);
      requireCell(what, row.columnInt(2), cellCount);
      portal.cellA = static_cast<uint32_t>(row.columnInt(1));
      portal.cellB = static_cast<uint32_t>(row.columnInt(2));
      const std::span<const uint8_t> blob = row.columnBlob(3);
      if (blob.size() % (3 * sizeof(float)) != 0 || blob.size() < 9 * sizeof(float))
        fail(fmt::format("{}: polygon blob of {} bytes is not 3 or more xyz float32 vertices", what, blob.size()));
      portal.polygon.resize(blob.size() / (3 * sizeof(float)));
      std::memcpy(portal.polygon.data(), blob.data(), blob.size());   // Vec3 is three packed floats
      portals.push_back(std::move(portal));
    }
    return portals;
  }

  // Version 1 stores have no hidden_from_camera column: nothing is hidden;
  // stores before version 5 no textures, before version 6 no glass.
  std::vector<Material> materials(int version) {
    std::vector<Material> materials;
    sql::Statement& row = db_.prepare(fmt::format(
        "SELECT id, name, albedo_r, albedo_g, albedo_b, emission_r, emission_g, emission_b, {}, {} "
        "FROM materials ORDER BY id",
        version >= 2 ? "hidden_from_camera" : "0",
        version >= 6 ? "transmittance_r, transmittance_g, transmittance_b, ior" : "0, 0, 0, 1.5"));
    while (row.step()) {
      requireDenseId("materials", row.columnInt(0), materials.size());
      Material material{static_cast<uint32_t>(row.columnInt(0)), row.columnText(1), columnVec3(row, 2),
                        columnVec3(row, 5)};
      material.hiddenFromCamera = row.columnInt(8) != 0;
      material.transmittance = columnVec3(row, 9);
      material.ior = static_cast<float>(row.columnDouble(12));
      materials.push_back(std::move(material));
    }
    if (version >= 5) {
      sql::Statement& texture = db_.prepare("SELECT material, albedo_texture FROM material_textures");
      while (texture.step()) {
        const int64_t id = texture.columnInt(0);
        if (id < 0 || static_cast<uint64_t>(id) >= materials.size())
          fail(fmt::format("material_textures names material {}, but there are {} materials", id, materials.size()));
        const std::string file = texture.columnText(1);
        // Only a file of the store's own textures/ folder: a worker opens it.
        const fs::path relative = fs::path(file).lexically_normal();
        if (relative.is_absolute() || relative.empty() || *relative.begin() != scene_schema::kTextureDirectory ||
            file.find("..") != std::string::npos)
          fail(fmt::format("material {}'s texture '{}' is not a file under textures/", id, file));
        materials[static_cast<size_t>(id)].albedoTexture = file;
      }
    }
    return materials;
  }

  std::vector<AreaLight> lights(size_t cellCount, int version) {
    std::vector<AreaLight> lights;
    sql::Statement& row = db_.prepare(fmt::format(
        "SELECT id, cell, corner_x, corner_y, corner_z, edge1_x, edge1_y, edge1_z, edge2_x, edge2_y, edge2_z, "
        "radiance_r, radiance_g, radiance_b, {} FROM lights ORDER BY id",
        version >= 3 ? "shape" : "'parallelogram'"));
    while (row.step()) {
      requireDenseId("lights", row.columnInt(0), lights.size());
      requireCell(fmt::format("light {}", row.columnInt(0)), row.columnInt(1), cellCount);
      AreaLight light;
      light.id = static_cast<uint32_t>(row.columnInt(0));
      light.cell = static_cast<uint32_t>(row.columnInt(1));
      light.corner = columnVec3(row, 2);
      light.edge1 = columnVec3(row, 5);
      light.edge2 = columnVec3(row, 8);
      light.radiance = columnVec3(row, 11);
      const std::string shape = row.columnText(14);
      if (shape != "parallelogram" && shape != "triangle" && shape != "point")
        fail(fmt::format("light {}: unknown shape '{}' (parallelogram, triangle or point)", light.id, shape));
      light.shape = shape == "triangle" ? LightShape::Triangle
                    : shape == "point"  ? LightShape::Point
                                        : LightShape::Parallelogram;
      lights.push_back(light);
    }
    if (version >= 8) readPointLights(lights, version);
    for (const AreaLight& light : lights)
      if (light.isPoint() && !light.intensity) fail(fmt::format("light {}: a point light without a distribution", light.id));
    return lights;
  }

  static std::vector<double> columnDoubles(const sql::Statement& row, int column) {
    const std::span<const uint8_t> blob = row.columnBlob(column);
    std::vector<double> values(blob.size() / sizeof(double));
    if (!values.empty()) std::memcpy(values.data(), blob.data(), values.size() * sizeof(double));
    return values;
  }

  // Each point luminaire's candela distribution (version 8 on) and
  // luminous opening (version 9 on).
  void readPointLights(std::vector<AreaLight>& lights, int version) {
    std::vector<std::shared_ptr<const LuminousIntensity>> distributions;
    sql::Statement& row =
        db_.prepare("SELECT id, name, vertical, horizontal, candela FROM light_distributions ORDER BY id");
    while (row.step()) {
      requireDenseId("light_distributions", row.columnInt(0), distributions.size());
      CandelaGrid grid{columnDoubles(row, 2), columnDoubles(row, 3), columnDoubles(row, 4)};
      if (const std::string problem = grid.problem(); !problem.empty())
        fail(fmt::format("light distribution {} ('{}'): {}", row.columnInt(0), row.columnText(1), problem));
      distributions.push_back(std::make_shared<const LuminousIntensity>(std::move(grid), row.columnText(1)));
    }
    sql::Statement& link = db_.prepare(fmt::format(
        "SELECT light, distribution, {} FROM point_lights ORDER BY light",
        version >= 9 ? "opening_width, opening_length, opening_height" : "0.0, 0.0, 0.0"));
    while (link.step()) {
      const int64_t light = link.columnInt(0), distribution = link.columnInt(1);
      if (light < 0 || size_t(light) >= lights.size() || !lights[size_t(light)].isPoint())
        fail(fmt::format("point_lights: light {} is not a point light", light));
      if (distribution < 0 || size_t(distribution) >= distributions.size())
        fail(fmt::format("light {}: unknown light distribution {}", light, distribution));
      lights[size_t(light)].intensity = distributions[size_t(distribution)];
      try {
        lights[size_t(light)].opening =
            LuminousOpening::fromLm63(link.columnDouble(2), link.columnDouble(3), link.columnDouble(4));
      } catch (const std::invalid_argument& e) {
        fail(fmt::format("light {}: {}", light, e.what()));
      }
    }
  }

  // Version 4 on: table cameras, the default first. Before: table camera,
  // one row, read as the camera named "default".
  std::vector<Camera> cameras(size_t cellCount, int version) {
    const bool named = version >= 4;
    sql::Statement& row = db_.prepare(fmt::format(
        "SELECT {}, origin_x, origin_y, origin_z, target_x, target_y, target_z, up_x, up_y, up_z, fov_y_deg, "
        "width, height, cell FROM {}",
        named ? "id, name" : fmt::format("0, '{}'", kDefaultCameraName), named ? "cameras ORDER BY id" : "camera"));
    std::vector<Camera> cameras;
    while (row.step()) {
      if (named) requireDenseId("cameras", row.columnInt(0), cameras.size());
      Camera camera;
      camera.name = row.columnText(1);
      camera.origin = columnVec3(row, 2);
      camera.target = columnVec3(row, 5);
      camera.up = columnVec3(row, 8);
      camera.fovYDegrees = static_cast<float>(row.columnDouble(11));
      camera.width = static_cast<uint32_t>(row.columnInt(12));
      camera.height = static_cast<uint32_t>(row.columnInt(13));
      requireCell(fmt::format("camera '{}'", camera.name), row.columnInt(14), cellCount);
      camera.cell = static_cast<uint32_t>(row.columnInt(14));
      cameras.push_back(std::move(camera));
    }
    row.reset();
    if (cameras.empty()) fail(fmt::format("table {} is empty", named ? "cameras" : "camera"));
    if (!named && cameras.size() > 1) fail("table camera has more than one row");
    return cameras;
  }

  // Version 7 on: zero or one row; before, no site.
  std::optional<SiteLocation> site(int version) {
    if (version < 7) return std::nullopt;
    sql::Statement& row = db_.prepare("SELECT latitude, longitude, north_azimuth FROM site");
    std::optional<SiteLocation> site;
    while (row.step()) {
      if (site) fail("table site has more than one row");
      site = SiteLocation{row.columnDouble(0), row.columnDouble(1), row.columnDouble(2)};
    }
    if (site)
      if (const std::string problem = siteLocationProblem(*site); !problem.empty()) fail("table site: " + problem);
    return site;
  }

 private:
  sql::Database& db_;
  fs::path directory_;
};

}  // namespace

SceneStore SceneStore::open(const std::string& directory) {
  fs::path path = fs::absolute(fs::path(directory)).lexically_normal();
  if (!path.has_filename()) path = path.parent_path();
  const auto fail = [&](const std::string& problem) {
    throw std::runtime_error(fmt::format("scene store {}: {}", path.string(), problem));
  };
  if (!fs::is_directory(path)) fail("no such directory");
  const fs::path databasePath = path / scene_schema::kDatabaseFile;
  if (!fs::is_regular_file(databasePath))
    fail("no scene.db in it; not a scene store (write one with `portico scene generate` or `portico scene import`)");

  SceneStore store;
  store.directory_ = path.string();
  try {
    sql::Database db(databasePath.string(), sql::Database::Mode::ReadOnly);
    const int version = db.userVersion();
    CatalogueReader reader(db, path);
    if (version < scene_schema::kOldestReadableVersion || version > scene_schema::kVersion)
      reader.fail(fmt::format(
          "scene.db has schema version {}, this build reads versions {} to {}; regenerate or re-import it", version,
          scene_schema::kOldestReadableVersion, scene_schema::kVersion));
    store.meta_ = reader.meta();
    store.cells_ = reader.cells();
    store.portals_ = reader.portals(store.cells_.size());
    store.materials_ = reader.materials(version);
    store.lights_ = reader.lights(store.cells_.size(), version);
    store.cameras_ = reader.cameras(store.cells_.size(), version);
    store.site_ = reader.site(version);
    store.indexByCell();
  } catch (const CatalogueError&) {
    throw;
  } catch (const std::runtime_error& e) {
    fail(fmt::format("cannot read scene.db: {}", e.what()));
  }
  return store;
}

void SceneStore::indexByCell() {
  const size_t cellCount = cells_.size();
  neighbours_.assign(cellCount, {});
  lightsByCell_.assign(cellCount, {});
  for (const Portal& portal : portals_) {
    if (portal.cellA >= cellCount || portal.cellB >= cellCount) continue;
    neighbours_[portal.cellA].push_back(portal.cellB);
    neighbours_[portal.cellB].push_back(portal.cellA);
  }
  for (const AreaLight& light : lights_)
    if (light.cell < cellCount) lightsByCell_[light.cell].push_back(light.id);
}

std::string SceneStore::cellPath(uint32_t cell) const {
  if (cell >= cells_.size())
    throw std::runtime_error(
        fmt::format("scene store {}: no cell {} (the store has {} cells)", directory_, cell, cells_.size()));
  return (fs::path(directory_) / cells_[cell].file).string();
}

const Camera* SceneStore::findCamera(std::string_view name) const {
  for (const Camera& camera : cameras_)
    if (camera.name == name) return &camera;
  return nullptr;
}

std::string SceneStore::cataloguePath() const {
  return (fs::path(directory_) / scene_schema::kDatabaseFile).string();
}

std::optional<uint32_t> SceneStore::locateCell(const Vec3& p) const {
  // Cells may nest (a room inside a voxel of a coarse grid) and touching
  // cells share their boundary planes: the smallest cell is the most specific.
  std::optional<uint32_t> best;
  double bestVolume = 0.0;
  for (const CellInfo& cell : cells_) {
    if (!cell.bounds.contains(p)) continue;
    const Vec3 d = cell.bounds.diagonal();
    const double volume = double{d.x} * double{d.y} * double{d.z};
    if (!best || volume < bestVolume) {
      best = cell.id;
      bestVolume = volume;
    }
  }
  return best;
}

uint64_t SceneStore::totalTriangles() const {
  uint64_t total = 0;
  for (const CellInfo& cell : cells_) total += cell.triangleCount;
  return total;
}

}  // namespace portico
