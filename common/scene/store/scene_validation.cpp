// validateSceneStore: the catalogue's cross references and geometry first
// (portals, lights, cameras), then every cell file through CellGeometry (the
// reader the workers use), compared with what the catalogue says of it.
#include "common/scene/store/scene_validation.h"

#include <fmt/format.h>

#include <algorithm>
#include <exception>
#include <filesystem>
#include <iterator>
#include <functional>
#include <memory>
#include <tuple>
#include <utility>

#include "common/scene/store/cell_geometry.h"
#include "common/scene/store/portal_geometry.h"

namespace portico {

namespace {

std::string formatVec(const Vec3& v) { return fmt::format("({}, {}, {})", v.x, v.y, v.z); }

class Validator {
 public:
  Validator(const SceneStore& store, CellFileCheck check)
      : store_(store), check_(check), portalsByCell_(store.cells().size()) {}

  std::vector<std::string> run() {
    checkCells();
    checkPortals();
    checkPortalsPerCell();
    checkLights();
    checkCameras();
    for (const CellInfo& cell : store_.cells()) {
      if (check_ == CellFileCheck::Read) checkCellFile(cell);
      else checkCellFileSize(cell);
    }
    return std::move(problems_);
  }

 private:
  bool cellExists(uint32_t id) const { return id < store_.cells().size(); }
  std::string cellName(uint32_t id) const {
    return cellExists(id) ? fmt::format("cell {} ('{}')", id, store_.cells()[id].name) : fmt::format("cell {}", id);
  }
  std::string missingCell(uint32_t id) const {
    return fmt::format("cell {} does not exist (the store has {} cells)", id, store_.cells().size());
  }
  bool nearlyContains(const Bounds3& box, const Vec3& p) const {
    const float tolerance = boxTolerance(box);
    return Bounds3(box.lo - Vec3(tolerance), box.hi + Vec3(tolerance)).contains(p);
  }
  template <typename... Args>
  void problem(fmt::format_string<Args...> format, Args&&... args) {
    problems_.push_back(fmt::format(format, std::forward<Args>(args)...));
  }

  void checkCells() {
    for (const CellInfo& cell : store_.cells())
      if (!isFinite(cell.bounds.lo) || !isFinite(cell.bounds.hi) || cell.bounds.empty())
        problem("{}: bounds {} - {} are not a finite, non-empty box", cellName(cell.id), formatVec(cell.bounds.lo),
                formatVec(cell.bounds.hi));
  }

  void checkPortals() {
    for (const Portal& portal : store_.portals()) {
      const std::string what = fmt::format("portal {} ({} - {})", portal.id, cellName(portal.cellA),
                                           cellName(portal.cellB));
      bool cellsExist = true;
      for (uint32_t cell : {portal.cellA, portal.cellB})
        if (!cellExists(cell)) {
          problem("{}: {}", what, missingCell(cell));
          cellsExist = false;
        }
      if (!cellsExist) continue;
      portalsByCell_[portal.cellA].push_back(portal.id);
      if (portal.cellA == portal.cellB) {
        problem("{}: joins a cell to itself", what);
        continue;
      }
      portalsByCell_[portal.cellB].push_back(portal.id);
      if (std::string shape = portalShapeProblem(portal.polygon); !shape.empty()) {
        problem("{}: polygon {}", what, shape);
        continue;
      }
      for (uint32_t cell : {portal.cellA, portal.cellB})
        if (std::string off = portalBoundaryProblem(store_.cells()[cell].bounds, portal.polygon); !off.empty())
          problem("{}: polygon is not on the boundary of {}: {}", what, cellName(cell), off);
    }
  }

  // Too many portals on a cell, or one given twice (same cells, same
  // polygon): either makes every ray in the cell test them all.
  void checkPortalsPerCell() {
    for (uint32_t cell = 0; cell < portalsByCell_.size(); ++cell) {
      std::vector<uint32_t> ids = portalsByCell_[cell];
      if (ids.size() > kMaxPortalsPerCell)
        problem("{}: has {} portals, more than {}", cellName(cell), ids.size(), kMaxPortalsPerCell);
      // Portals of this cell ordered by (their cells, their polygon's points).
      const auto order = [&](uint32_t a, uint32_t b) {
        const Portal& p = store_.portals()[a];
        const Portal& q = store_.portals()[b];
        const auto cells = [](const Portal& x) { return std::make_pair(std::min(x.cellA, x.cellB), std::max(x.cellA, x.cellB)); };
        if (cells(p) != cells(q)) return cells(p) < cells(q);
        return std::lexicographical_compare(p.polygon.begin(), p.polygon.end(), q.polygon.begin(), q.polygon.end(),
                                            [](const Vec3& u, const Vec3& v) {
                                              return std::tie(u.x, u.y, u.z) < std::tie(v.x, v.y, v.z);
                                            });
      };
      std::sort(ids.begin(), ids.end(), order);
      // Reported from the lower cell of each pair, the first in full, then counted.
      size_t duplicates = 0;
      for (size_t i = 1; i < ids.size(); ++i) {
        const Portal& portal = store_.portals()[ids[i]];
        if (cell != std::min(portal.cellA, portal.cellB) || order(ids[i - 1], ids[i])) continue;
        if (duplicates++ == 0)
          problem("portal {}: duplicates portal {} (between {} and {})", ids[i], ids[i - 1], cellName(portal.cellA),
                  cellName(portal.cellB));
      }
      if (duplicates > 1) problem("{}: {} more duplicate portals", cellName(cell), duplicates - 1);
    }
  }

  void checkLights() {
    for (const AreaLight& light : store_.lights()) {
      const std::string what = fmt::format("light {}", light.id);
      if (!cellExists(light.cell)) {
        problem("{}: {}", what, missingCell(light.cell));
        continue;
      }
      if (!isFinite(light.corner) || !isFinite(light.edge1) || !isFinite(light.edge2) ||
          !(light.isPoint() || light.area() > 0.0f)) {
        problem("{}: corner or edges are not finite, or its area is zero", what);
        continue;
      }
      if (!nearlyContains(store_.cells()[light.cell].bounds, light.center()))
        problem("{}: its centre {} lies outside the bounds of its {}", what, formatVec(light.center()),
                cellName(light.cell));
    }
  }

  void checkCameras() {
    for (const Camera& camera : store_.cameras()) {
      if (!cellExists(camera.cell))
        problem("camera '{}': {}", camera.name, missingCell(camera.cell));
      else if (!nearlyContains(store_.cells()[camera.cell].bounds, camera.origin))
        problem("camera '{}': origin {} lies outside the bounds of its {}", camera.name, formatVec(camera.origin),
                cellName(camera.cell));
    }
  }

  void checkCellFileSize(const CellInfo& cell) {
    const std::string path = store_.cellPath(cell.id);
    std::error_code error;
    const uintmax_t size = std::filesystem::file_size(path, error);
    if (error) problem("cell file {}: cannot be read: {}", path, error.message());
    else if (size != cell.byteCount) problem("cell file {}: is {} bytes, the catalogue says {}", path, size, cell.byteCount);
  }

  // The file must load as the workers load it (format, id, index and
  // material ranges, finite positions) and agree with the catalogue.
  void checkCellFile(const CellInfo& cell) {
    const std::string path = store_.cellPath(cell.id);
    std::unique_ptr<CellGeometry> geometry;
    try {
      geometry = CellGeometry::load(path, cell.id, store_.materials().size());
    } catch (const std::exception& e) {
      problems_.push_back(e.what());   // names the file and the problem
      return;
    }
    const std::string what = fmt::format("cell file {}", path);
    if (geometry->mesh().triangleCount != cell.triangleCount)
      problem("{}: holds {} triangles, the catalogue says {}", what, geometry->mesh().triangleCount,
              cell.triangleCount);
    if (geometry->bytes() != cell.byteCount)
      problem("{}: is {} bytes, the catalogue says {}", what, geometry->bytes(), cell.byteCount);
    if (!(geometry->bounds().lo == cell.bounds.lo && geometry->bounds().hi == cell.bounds.hi))
      problem("{}: bounds {} - {} differ from the catalogue's {} - {}", what, formatVec(geometry->bounds().lo),
              formatVec(geometry->bounds().hi), formatVec(cell.bounds.lo), formatVec(cell.bounds.hi));

    // The portals listed in the file are the catalogue's portals of this cell.
    std::vector<std::pair<uint32_t, uint32_t>> listed;   // (portal, neighbour)
    for (const CellPortalView& view : geometry->portals()) {
      listed.emplace_back(view.portalId, view.neighborCell);
      if (view.portalId < store_.portals().size() && view.polygon != store_.portals()[view.portalId].polygon)
        problem("{}: the polygon of portal {} differs from the catalogue's", what, view.portalId);
    }
    std::vector<std::pair<uint32_t, uint32_t>> expected;
    for (uint32_t id : portalsByCell_[cell.id]) {
      const Portal& portal = store_.portals()[id];
      expected.emplace_back(id, portal.cellA == cell.id ? portal.cellB : portal.cellA);
    }
    std::sort(listed.begin(), listed.end());
    std::sort(expected.begin(), expected.end());
    std::vector<std::pair<uint32_t, uint32_t>> extra, absent;
    std::set_difference(listed.begin(), listed.end(), expected.begin(), expected.end(), std::back_inserter(extra));
    std::set_difference(expected.begin(), expected.end(), listed.begin(), listed.end(), std::back_inserter(absent));
    for (const auto& [portal, neighbour] : extra)
      problem("{}: lists portal {} to cell {}, which the catalogue does not have", what, portal, neighbour);
    for (const auto& [portal, neighbour] : absent)
      problem("{}: does not list portal {} to cell {}", what, portal, neighbour);
  }

  const SceneStore& store_;
  CellFileCheck check_;
  std::vector<std::vector<uint32_t>> portalsByCell_;
  std::vector<std::string> problems_;
};

}  // namespace

std::vector<std::string> validateSceneStore(const SceneStore& store, CellFileCheck check) {
  return Validator(store, check).run();
}

}  // namespace portico
