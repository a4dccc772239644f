#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <optional>

#include "common/photometry/ies_file.h"
#include "common/photometry/luminous_intensity.h"
#include "common/scene/generator/building_generator.h"
#include "common/scene/import/building_importer.h"
#include "common/scene/generator/demo_generator.h"
#include "common/scene/store/floor_levels.h"
#include "common/scene/store/scene_store.h"
#include "common/scene/store/scene_validation.h"
#include "coordinator/cli/compressed_size.h"
#include "coordinator/cli/commands.h"
#include "coordinator/cli/ifc_conversion.h"
#include "coordinator/cli/scene_import_ifc.h"

namespace portico::cli {

int runSceneGenerate(const std::string& preset, uint64_t seed, uint32_t floors, const std::string& store,
                     const PanelLighting& panels) {
  // Refused before a store is begun.
  if (const std::string problem = panelLightingProblem(panels); !problem.empty()) throw std::invalid_argument(problem);
  if (preset == "demo") {
    if (floors > 1) std::cerr << "portico: the demo preset has one floor; --floors ignored\n";
    generateDemoBuilding(store, seed, panels);
  } else if (const std::optional<BuildingPreset> building = findBuildingPreset(preset, floors)) {
    if (floors != 0 && preset != "tower")
      std::cerr << fmt::format("portico: preset {} has {} floors; --floors is for the tower\n", preset, building->floors);
    const GeneratedBuildingStats stats = generateBuilding(*building, seed, store, panels);
    std::cerr << fmt::format("portico: generated {} ({} triangles, {} cells) in {:.1f} s: {:.2f} M triangles/s\n",
                             preset, stats.triangles, stats.cells, stats.seconds,
                             double(stats.triangles) / std::max(1e-9, stats.seconds) / 1e6);
  } else {
    std::cerr << fmt::format("portico: unknown preset '{}' (known: demo, {})\n", preset,
                             fmt::join(buildingPresetNames(), ", "));
    return 2;
  }
  return runSceneInfo(store, false);
}

namespace {
constexpr size_t kObjectsWorthProgress = 1000;

std::string horizontalSymmetry(const CandelaGrid& grid) {
  if (grid.horizontal.size() == 1) return "the same all around";
  if (grid.horizontal.front() == 90.0) return "mirrored across C90-C270";
  if (grid.horizontal.back() == 90.0) return "four mirrored quadrants";
  if (grid.horizontal.back() == 180.0) return "mirrored across C0-C180";
  return "no symmetry";
}
}  // namespace

int runSceneIes(const std::vector<std::string>& files) {
  int status = 0;
  for (const std::string& file : files) {
    try {
      const IesPhotometry ies = readIesFile(file);
      const LuminousIntensity intensity(ies.grid, file);
      const double peak = *std::max_element(ies.grid.candela.begin(), ies.grid.candela.end());
      std::cout << fmt::format(
          "{}: {}, {} vertical x {} horizontal angles ({}), peak {:.1f} cd, {:.2f} lm; lamps: {}; opening: {}\n", file,
          ies.standard, ies.grid.vertical.size(), ies.grid.horizontal.size(), horizontalSymmetry(ies.grid), peak,
          intensity.lumens(),
          ies.ratedLumens() < 0 ? std::string("absolute photometry")
                                : fmt::format("{} x {} lm rated", ies.lampCount, ies.lumensPerLamp),
          ies.opening.describe());
    } catch (const std::runtime_error& e) {
      std::cerr << "portico: " << e.what() << "\n";
      status = 1;
    }
  }
  return status;
}

int runSceneImport(const std::vector<std::string>& inputs, const ImportOptions& options, const std::string& store,
                   const IfcOptions& ifc) {
  // Progress on stderr, once a second, for imports of many objects (a
  // mesh file costs a few milliseconds to read).
  ImportOptions withProgress = options;
  const auto started = std::chrono::steady_clock::now();
  auto lastShown = started;
  withProgress.onMeshRead = [&](size_t read, size_t objects) {
    const auto now = std::chrono::steady_clock::now();
    if (objects < kObjectsWorthProgress || (now - lastShown < std::chrono::seconds(1) && read != objects && read != 1))
      return;
    lastShown = now;
    std::cerr << fmt::format("reading mesh files: {} of {} objects ({:.0f} %, {:.1f} s)\n", read, objects,
                             100.0 * double(read) / double(objects),
                             std::chrono::duration<double>(now - started).count());
  };
  std::string lastStage;
  withProgress.rooms.onProgress = [&](const std::string& stage, double fraction) {
    const auto now = std::chrono::steady_clock::now();
    // Only for searches long enough to wonder about (a building of a few floors takes under a second).
    if (now - started < std::chrono::seconds(1) || (stage == lastStage && now - lastShown < std::chrono::seconds(1)))
      return;
    lastStage = stage;
    lastShown = now;
    std::cerr << fmt::format("finding rooms: {} ({:.0f} %, {:.1f} s)\n", stage, 100.0 * fraction,
                             std::chrono::duration<double>(now - started).count());
  };
  withProgress.onRoomsFound = [&](uint32_t rooms, size_t cells, size_t portals) {   // always: what was found
    std::cerr << fmt::format("found {} rooms: {} box cells, {} portals ({:.1f} s)\n", rooms, cells, portals,
                             std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count());
  };
  ImportSummary summary;
  if (inputs.size() == 1 && isIfcFile(inputs[0])) {
    IfcOptions withRooms = ifc;
    withRooms.findRooms = ifc.findRooms || options.findRooms;
    summary = importIfcModel(inputs[0], store, withProgress, withRooms);
  } else {
    summary = importBuilding(inputs, store, withProgress);
  }
  const int status = runSceneInfo(store, false);
  for (const std::string& warning : summary.warnings) std::cerr << "portico: warning: " << warning << "\n";
  return status;
}

namespace {

std::string formatBytes(uint64_t bytes) {
  const char* const units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  double value = double(bytes);
  int unit = 0;
  while (value >= 1024 && unit < 4) value /= 1024, ++unit;
  return unit == 0 ? fmt::format("{} B", bytes) : fmt::format("{:.1f} {}", value, units[unit]);
}

// Table 2's columns: the store's files as they lie on disk (cell files and
// scene.db), and the same files each deflated by zlib.
struct StoreBytes {
  uint64_t raw = 0;
  std::optional<uint64_t> compressed;
};

StoreBytes measureStore(const SceneStore& store, bool compress) {
  namespace fs = std::filesystem;
  std::vector<std::string> files{store.cataloguePath()};
  for (const CellInfo& cell : store.cells()) files.push_back(store.cellPath(cell.id));
  StoreBytes bytes;
  if (compress) bytes.compressed = 0;
  for (const std::string& file : files) {
    std::error_code error;
    const uintmax_t size = fs::file_size(file, error);
    if (error) continue;   // a missing cell file is the validation's to report
    bytes.raw += size;
    if (compress) *bytes.compressed += zlibCompressedSize(file);
  }
  return bytes;
}

}  // namespace

int runSceneInfo(const std::string& directory, bool json) {
  return runSceneInfo(directory, SceneInfoOptions{json, /*compress=*/false, /*readCells=*/false});
}

namespace {
std::array<float, 3> xyz(const Vec3& v) { return {v.x, v.y, v.z}; }

// Every named camera, as `render --camera NAME` takes it.
nlohmann::json camerasJson(const SceneStore& store) {
  nlohmann::json cameras = nlohmann::json::array();
  for (const Camera& camera : store.cameras())
    cameras.push_back({{"name", camera.name},
                       {"cell", camera.cell},
                       {"origin", xyz(camera.origin)},
                       {"look_at", xyz(camera.target)},
                       {"up", xyz(camera.up)},
                       {"fov", camera.fovYDegrees},
                       {"width", camera.width},
                       {"height", camera.height}});
  return cameras;
}

// "cameras (N): a, b, c, ... and M more": a tower's hundreds stay one line.
std::string describeCameraNames(const SceneStore& store) {
  constexpr size_t kListed = 8;
  const std::vector<Camera>& cameras = store.cameras();
  std::string line = fmt::format("cameras ({}, --camera NAME; the first is the default):", cameras.size());
  for (size_t k = 0; k < std::min(kListed, cameras.size()); ++k) line += (k ? ", " : " ") + cameras[k].name;
  if (cameras.size() > kListed) line += fmt::format(" and {} more (--json lists them)", cameras.size() - kListed);
  return line;
}
}  // namespace

int runSceneInfo(const std::string& directory, const SceneInfoOptions& options) {
  const SceneStore store = SceneStore::open(directory);
  uint64_t maxTriangles = 0, emptyCells = 0;
  for (const CellInfo& cell : store.cells()) {
    maxTriangles = std::max(maxTriangles, cell.triangleCount);
    emptyCells += cell.triangleCount == 0 ? 1 : 0;
  }
  const double avgTriangles = double(store.totalTriangles()) / double(std::max<size_t>(1, store.cells().size()));
  const uint32_t floors = floorCount(store);
  const StoreBytes bytes = measureStore(store, options.compress);
  const std::vector<std::string> problems =
      validateSceneStore(store, options.readCells ? CellFileCheck::Read : CellFileCheck::Size);

  nlohmann::json info;
  info["store"] = store.directory();
  info["cells"] = store.cells().size();
  info["empty_cells"] = emptyCells;
  info["portals"] = store.portals().size();
  info["lights"] = store.lights().size();
  info["materials"] = store.materials().size();
  info["floors"] = floors;
  info["level_kind"] = levelWord(store);
  info["triangles"] = store.totalTriangles();
  info["avg_triangles_per_cell"] = avgTriangles;
  info["max_triangles_per_cell"] = maxTriangles;
  info["bytes"] = bytes.raw;
  info["bytes_compressed"] = bytes.compressed ? nlohmann::json(*bytes.compressed) : nlohmann::json(nullptr);
  info["valid"] = problems.empty();
  info["problems"] = problems;
  info["meta"] = store.meta();
  const Camera& camera = store.camera();
  info["camera"] = {{"origin", {camera.origin.x, camera.origin.y, camera.origin.z}},
                    {"target", {camera.target.x, camera.target.y, camera.target.z}},
                    {"fov_y_deg", camera.fovYDegrees},
                    {"width", camera.width},
                    {"height", camera.height},
                    {"cell", camera.cell}};
  info["cameras"] = camerasJson(store);
  info["site"] = store.site() ? nlohmann::json{{"latitude", store.site()->latitudeDegrees},
                                               {"longitude", store.site()->longitudeDegrees},
                                               {"north_azimuth", store.site()->northAzimuthDegrees}}
                              : nlohmann::json(nullptr);
  nlohmann::json cells = nlohmann::json::array();
  for (const CellInfo& cell : store.cells())
    cells.push_back({{"id", cell.id}, {"name", cell.name}, {"triangles", cell.triangleCount}, {"bytes", cell.byteCount}});
  info["cell_list"] = cells;
  if (options.json) {
    std::cout << info.dump() << "\n";
    return problems.empty() ? 0 : 1;
  }

  std::cout << fmt::format("{}: {} cells, {} portals, {} lights, {} {}{}, {} materials, {} triangles\n",
                           store.directory(), store.cells().size(), store.portals().size(), store.lights().size(),
                           floors, levelWord(store), floors == 1 ? "" : "s", store.materials().size(),
                           store.totalTriangles());
  std::cout << fmt::format("triangles per cell: avg {:.1f}, max {} ({} cell{} without triangles)\n", avgTriangles,
                           maxTriangles, emptyCells, emptyCells == 1 ? "" : "s");
  if (bytes.compressed)
    std::cout << fmt::format("on disk: {} ({} bytes), zlib-compressed {} ({} bytes, {:.0f} %)\n",
                             formatBytes(bytes.raw), bytes.raw, formatBytes(*bytes.compressed), *bytes.compressed,
                             100.0 * double(*bytes.compressed) / double(std::max<uint64_t>(1, bytes.raw)));
  else
    std::cout << fmt::format("on disk: {} ({} bytes)\n", formatBytes(bytes.raw), bytes.raw);
  if (auto it = store.meta().find("degenerate_triangles_dropped"); it != store.meta().end() && it->second != "0")
    std::cout << fmt::format("import dropped {} degenerate triangles\n", it->second);
  std::cout << fmt::format("camera: {}x{} in cell {}{}\n", camera.width, camera.height, camera.cell,
                           camera.cell < store.cells().size() ? fmt::format(" ('{}')", store.cells()[camera.cell].name)
                                                              : std::string());
  std::cout << describeCameraNames(store) << "\n";
  if (const auto& site = store.site())
    std::cout << fmt::format("site: latitude {}, longitude {}, north at azimuth {} (for --sun-time)\n",
                             site->latitudeDegrees, site->longitudeDegrees, site->northAzimuthDegrees);
  // A store of 10^4 cells would bury the summary: list the largest few.
  constexpr size_t kListedCells = 64, kLargestCells = 10;
  std::vector<const CellInfo*> listed;
  for (const CellInfo& cell : store.cells()) listed.push_back(&cell);
  if (listed.size() > kListedCells) {
    std::stable_sort(listed.begin(), listed.end(),
                     [](const CellInfo* a, const CellInfo* b) { return a->triangleCount > b->triangleCount; });
    listed.resize(kLargestCells);
    std::cout << fmt::format("the {} largest of {} cells (--json lists every cell):\n", kLargestCells,
                             store.cells().size());
  }
  for (const CellInfo* cell : listed)
    std::cout << fmt::format("  cell {:4} {:20} {:8} triangles {:10} bytes\n", cell->id, cell->name,
                             cell->triangleCount, cell->byteCount);
  if (problems.empty()) {
    std::cout << (options.readCells
                      ? "valid: portals on their cells' boundaries, no dangling ids, every cell file readable\n"
                      : "valid: portals on their cells' boundaries, no dangling ids, every cell file at its size "
                        "(`scene info` reads them)\n");
    return 0;
  }
  std::cout << fmt::format("INVALID: {} problem{}\n", problems.size(), problems.size() == 1 ? "" : "s");
  for (const std::string& problem : problems) std::cout << "  " << problem << "\n";
  return 1;
}

}  // namespace portico::cli
