#include "coordinator/cli/scene_export.h"

#include <fmt/format.h>
#include <fmt/os.h>

#include <filesystem>
#include <iostream>
#include <memory>
#include <stdexcept>

#include "common/scene/store/cell_geometry.h"
#include "common/scene/store/scene_store.h"
#include "coordinator/cli/export_groups.h"
#include "coordinator/cli/scene_export_gltf.h"
#include "coordinator/cli/scene_export_radiance.h"

namespace portico::cli {

namespace {

std::string materialName(const Material& m) { return fmt::format("m{}", m.id); }

void writeMtl(const SceneStore& store, const std::string& path) {
  auto out = fmt::output_file(path);
  out.print("# materials of scene store {}\n", store.directory());
  for (const Material& m : store.materials()) {
    out.print("# {}\nnewmtl {}\nKd {} {} {}\n", m.name, materialName(m), m.albedo.x, m.albedo.y, m.albedo.z);
    if (m.emissive()) out.print("Ke {} {} {}\n", m.emission.x, m.emission.y, m.emission.z);
  }
}

void writeComments(const SceneStore& store, fmt::ostream& out) {
  for (const Portal& p : store.portals()) {
    out.print("# portal {} {}", store.cells()[p.cellA].name, store.cells()[p.cellB].name);
    for (const Vec3& v : p.polygon) out.print(" {} {} {}", v.x, v.y, v.z);
    out.print("\n");
  }
  const Camera& c = store.camera();
  out.print("# camera origin {} {} {} target {} {} {} up {} {} {} fov_y_deg {} size {}x{}\n", c.origin.x, c.origin.y,
            c.origin.z, c.target.x, c.target.y, c.target.z, c.up.x, c.up.y, c.up.z, c.fovYDegrees, c.width, c.height);
}

}  // namespace

ExportSummary exportStoreObj(const std::string& directory, const std::string& objPath) {
  namespace fs = std::filesystem;
  if (fs::path(objPath).extension() != ".obj")
    throw std::runtime_error(
        fmt::format("{}: export writes Wavefront OBJ (+ MTL), glTF or Radiance; name the file *.obj, *.glb, *.gltf or *.rad", objPath));
  const SceneStore store = SceneStore::open(directory);
  const std::string mtlPath = fs::path(objPath).replace_extension(".mtl").string();
  writeMtl(store, mtlPath);
  auto out = fmt::output_file(objPath);
  out.print("# scene store {}: {} cells, {} portals\nmtllib {}\n", store.directory(), store.cells().size(),
            store.portals().size(), fs::path(mtlPath).filename().string());
  writeComments(store, out);
  ExportSummary summary;
  uint64_t vertexBase = 1;
  for (const CellInfo& cell : store.cells()) {
    const std::unique_ptr<CellGeometry> geometry =
        CellGeometry::load(store.cellPath(cell.id), cell.id, store.materials().size());
    const MeshView& mesh = geometry->mesh();
    uint32_t lamp = 0;
    for (const TriangleGroup& group : exportGroups(*geometry, store.materials())) {
      if (group.lamp)
        out.print("o {}-lamp-{}\n", cell.name, lamp++);
      else
        out.print("o {}\n", cell.name);
      out.print("usemtl {}\n", materialName(store.materials()[group.material]));
      for (uint32_t t : group.triangles) {
        Vec3 v[3];
        mesh.triangle(t, v[0], v[1], v[2]);
        for (const Vec3& p : v) {
          out.print("v {} {} {}\n", p.x, p.y, p.z);
          summary.bounds.extend(p);
        }
        out.print("f {} {} {}\n", vertexBase, vertexBase + 1, vertexBase + 2);
        vertexBase += 3;
        ++summary.triangles;
      }
    }
  }
  return summary;
}

int runSceneExport(const std::string& store, const std::string& output, const DaylightSettings& daylight) {
  if (isRadiancePath(output)) {
    const ExportSummary s = exportStoreRadiance(store, output, daylight);
    std::cout << fmt::format("{}: {} triangles as {} polygons, {} materials, bounds ({}, {}, {}) - ({}, {}, {}){}{}\n",
                             output, s.triangles, s.polygons, s.materials, s.bounds.lo.x, s.bounds.lo.y, s.bounds.lo.z,
                             s.bounds.hi.x, s.bounds.hi.y, s.bounds.hi.z,
                             s.luminaires ? fmt::format("; {} IES luminaires as light spheres", s.luminaires) : "",
                             s.skyFile.empty() ? "" : "; daylight in " + s.skyFile);
    return 0;
  }
  if (daylight.any())
    throw std::runtime_error(fmt::format("{}: --sky and --sun are for a Radiance export (FILE.rad) only", output));
  const ExportSummary s = isGltfPath(output) ? exportStoreGltf(store, output) : exportStoreObj(store, output);
  std::cout << fmt::format("{}: {} triangles, bounds ({}, {}, {}) - ({}, {}, {})\n", output, s.triangles, s.bounds.lo.x,
                           s.bounds.lo.y, s.bounds.lo.z, s.bounds.hi.x, s.bounds.hi.y, s.bounds.hi.z);
  return 0;
}

}  // namespace portico::cli
