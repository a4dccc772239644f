#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <iostream>

#include "common/scene/building_importer.h"
#include "common/scene/demo_generator.h"
#include "common/scene/scene_store.h"
#include "coordinator/cli/commands.h"

namespace portico::cli {

int runSceneGenerate(const std::string& preset, uint64_t seed, uint32_t floors, const std::string& store) {
  if (preset == "demo") {
    if (floors != 1) std::cerr << "portico: the demo preset has one floor; --floors ignored\n";
    generateDemoBuilding(store, seed);
  } else {
    std::cerr << fmt::format("portico: unknown preset '{}' (known: demo)\n", preset);
    return 2;
  }
  return runSceneInfo(store, false);
}

int runSceneImport(const std::vector<std::string>& inputs, const ImportOptions& options, const std::string& store) {
  importBuilding(inputs, store, options);
  return runSceneInfo(store, false);
}

int runSceneInfo(const std::string& directory, bool json) {
  const SceneStore store = SceneStore::open(directory);
  uint64_t maxTriangles = 0;
  for (const CellInfo& cell : store.cells()) maxTriangles = std::max(maxTriangles, cell.triangleCount);
  nlohmann::json info;
  info["store"] = store.directory();
  info["cells"] = store.cells().size();
  info["portals"] = store.portals().size();
  info["lights"] = store.lights().size();
  info["materials"] = store.materials().size();
  info["triangles"] = store.totalTriangles();
  info["max_triangles_per_cell"] = maxTriangles;
  const Camera& camera = store.camera();
  info["camera"] = {{"origin", {camera.origin.x, camera.origin.y, camera.origin.z}},
                    {"target", {camera.target.x, camera.target.y, camera.target.z}},
                    {"fov_y_deg", camera.fovYDegrees},
                    {"width", camera.width},
                    {"height", camera.height},
                    {"cell", camera.cell}};
  nlohmann::json cells = nlohmann::json::array();
  for (const CellInfo& cell : store.cells())
    cells.push_back({{"id", cell.id}, {"name", cell.name}, {"triangles", cell.triangleCount}, {"bytes", cell.byteCount}});
  info["cell_list"] = cells;
  if (json) {
    std::cout << info.dump() << "\n";
    return 0;
  }
  std::cout << fmt::format("{}: {} cells, {} portals, {} lights, {} materials, {} triangles (max {} per cell)\n",
                           store.directory(), store.cells().size(), store.portals().size(), store.lights().size(),
                           store.materials().size(), store.totalTriangles(), maxTriangles);
  std::cout << fmt::format("camera: {}x{} in cell {}\n", camera.width, camera.height, camera.cell);
  for (const CellInfo& cell : store.cells())
    std::cout << fmt::format("  cell {:4} {:20} {:8} triangles {:10} bytes\n", cell.id, cell.name, cell.triangleCount,
                             cell.byteCount);
  return 0;
}

}  // namespace portico::cli
