// The building importer: reads a building.json or mesh files into an
// ImportedScene (every check done here, before the store exists), then
// writes it with the given cells or as voxel cells.
#include "common/scene/import/building_importer.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>

#include "common/photometry/lamp_colour.h"
#include "common/scene/import/building_json.h"
#include "common/scene/import/store_scene_reader.h"
#include "common/scene/import/imported_scene.h"
#include "common/scene/import/mesh_loader.h"
#include "common/scene/import/quad_light.h"
#include "common/scene/import/room_lighting.h"
#include "common/scene/store/scene_store.h"
#include "common/scene/import/voxel_cells.h"
#include "common/util/temporary_directory.h"

namespace portico {

namespace fs = std::filesystem;

namespace {

constexpr float kCellPadding = 1e-3f;        // 1 mm around the scene for a cell we make
constexpr float kCellTolerance = 1e-3f;      // triangles may stick out of their cell by this much of the scene size
const char* const kSingleCellName = "building";
const char* const kNoLightsWarning =
    "the scene has no lights, so `portico render` refuses it unless daylight lights it (--sun or --sky through "
    "portals to outdoor cells, docs/daylight.md); add one with a \"lights\" array in a building.json (quads and triangles, docs/building-json.md), an emissive material in a mesh file "
    "(MTL Ke, glTF emissiveFactor), or, for an IFC model, --lights panels";

std::string formatVec(const Vec3& v) { return fmt::format("({}, {}, {})", v.x, v.y, v.z); }

bool isBuildingJson(const std::string& path) {
  std::string extension = fs::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension == ".json";
}

Bounds3 padded(const Bounds3& box) { return Bounds3(box.lo - Vec3(kCellPadding), box.hi + Vec3(kCellPadding)); }

// Materials, one per distinct (albedo, emission, texture, glass); the first name wins.
class MaterialTable {
 public:
  uint32_t add(const std::string& name, const Vec3& albedo, const Vec3& emission, std::vector<ImportedMaterial>& out,
               const std::string& albedoTexture = {}, const Vec3& transmittance = Vec3(0), float ior = 1.5f) {
    const std::array<float, 10> colours{albedo.x,        albedo.y,        albedo.z,        emission.x, emission.y,
                                       emission.z,      transmittance.x, transmittance.y, transmittance.z, ior};
    auto [it, inserted] = ids_.emplace(std::make_pair(colours, albedoTexture), static_cast<uint32_t>(out.size()));
    if (inserted) out.push_back(ImportedMaterial{name, albedo, emission, false, albedoTexture, transmittance, ior});
    return it->second;
  }

 private:
  std::map<std::pair<std::array<float, 10>, std::string>, uint32_t> ids_;
};

void appendPart(const MeshFilePart& part, ImportedObject& object) {
  const auto offset = static_cast<uint32_t>(object.positions.size() / 3);
  object.positions.insert(object.positions.end(), part.positions.begin(), part.positions.end());
  for (uint32_t index : part.indices) object.indices.push_back(offset + index);
}

void extendBounds(Bounds3& bounds, const ImportedObject& object) {
  for (size_t v = 0; v < object.positions.size() / 3; ++v) bounds.extend(object.vertex(static_cast<uint32_t>(v)));
}

// An emissive object's lights: one quad light where it is a parallelogram of
// two triangles (every lamp portico writes), otherwise one triangle light
// per triangle, so any shape emits with its own area and radiance.
void addEmitter(const ImportedObject& object, const Vec3& radiance, ImportedScene& scene) {
  std::string problem;
  if (const std::optional<Parallelogram> quad = parallelogramFromTriangles(object.positions, object.indices, problem)) {
    scene.lights.push_back(ImportedLight{object.label, object.cell, *quad, radiance});
    return;
  }
  for (size_t t = 0; t < object.triangleCount(); ++t) {
    const Vec3 a = object.vertex(object.indices[3 * t]), b = object.vertex(object.indices[3 * t + 1]),
               c = object.vertex(object.indices[3 * t + 2]);
    scene.lights.push_back(ImportedLight{fmt::format("{} triangle {}", object.label, t), object.cell,
                                         Parallelogram{a, b - a, c - a}, radiance, LightShape::Triangle});
  }
}

// The parts of a mesh file as objects with the file's own materials (diffuse
// colour clamped to [0, 1]; emissive colour, or `emissionOverride`, as
// radiance); emissive parts become lights.
void addPartsWithFileMaterials(const LoadedMeshFile& mesh, const std::string& labelPrefix, uint32_t cell,
                               const std::optional<Vec3>& emissionOverride, MaterialTable& materials,
                               ImportedScene& scene) {
  for (const MeshFilePart& part : mesh.parts) {
    const MeshFileMaterial& source = mesh.materials[part.material];
    const std::string label = fmt::format("{}: part '{}'", labelPrefix, part.name);
    if (!isFinite(source.diffuse) || !isFinite(source.emissive))
      throw std::runtime_error(fmt::format("{}: material '{}' has a colour that is not finite", label, source.name));
    // A transparent material is thin glass, without diffuse reflection.
    const Vec3 transmittance = min(max(source.transmittance, Vec3(0.0f)), Vec3(1.0f));
    const bool glass = maxComponent(transmittance) > 0.0f;
    const Vec3 albedo = glass ? Vec3(0.0f) : min(max(source.diffuse, Vec3(0.0f)), Vec3(1.0f));
    const Vec3 emission = emissionOverride ? *emissionOverride : max(source.emissive, Vec3(0.0f));
    ImportedObject object;
    object.label = label;
    object.cell = cell;
    appendPart(part, object);
    // A texture needs the part's uvs; a part without them keeps the colour.
    const bool textured = !source.diffuseTexture.empty() && !part.uvs.empty();
    if (textured) object.uvs = part.uvs;
    object.material = materials.add(source.name, albedo, emission, scene.materials,
                                    textured ? source.diffuseTexture : std::string(), transmittance);
    if (maxComponent(emission) > 0.0f) addEmitter(object, emission, scene);
    scene.objects.push_back(std::move(object));
  }
}

// The smallest of `cells` containing p (cells may touch), if any.
std::optional<uint32_t> smallestCellContaining(const std::vector<ImportedCell>& cells, const Vec3& p) {
  std::optional<uint32_t> best;
  float bestVolume = kInfinity;
  for (uint32_t c = 0; c < cells.size(); ++c) {
    if (!cells[c].bounds.contains(p)) continue;
    const Vec3 d = cells[c].bounds.diagonal();
    if (d.x * d.y * d.z < bestVolume) {
      bestVolume = d.x * d.y * d.z;
      best = c;
    }
  }
  return best;
}

const BuildingCamera& chooseCamera(const BuildingDescription& building, const std::string& name) {
  if (name.empty()) return building.cameras.front();
  std::string known;
  for (const BuildingCamera& camera : building.cameras) {
    if (camera.name == name) return camera;
    known += (known.empty() ? "" : ", ") + camera.name;
  }
  throw std::runtime_error(fmt::format("{}: no camera named '{}' (known: {})", building.path, name, known));
}

// Every triangle of every object within its cell's box (grown by the tolerance).
void checkObjectsInCells(const ImportedScene& scene, const std::string& path) {
  const float tolerance = kCellTolerance * std::max(1.0f, maxComponent(scene.bounds.diagonal()));
  for (const ImportedObject& object : scene.objects) {
    const ImportedCell& cell = scene.cells[object.cell];
    const Bounds3 grown(cell.bounds.lo - Vec3(tolerance), cell.bounds.hi + Vec3(tolerance));
    for (uint32_t index : object.indices) {
      const Vec3 p = object.vertex(index);
      if (!grown.contains(p))
        throw std::runtime_error(fmt::format("{}: {}: vertex {} lies outside the aabb of its cell '{}' ({} - {})", path,
                                             object.label, formatVec(p), cell.name, formatVec(cell.bounds.lo),
                                             formatVec(cell.bounds.hi)));
    }
  }
}

// An entry of the building.json's "lights": its triangles (an emissive,
// black material) and the light itself.
void addGivenLight(const BuildingLight& given, uint32_t cell, MaterialTable& materials, ImportedScene& scene) {
  if (given.shape == LightShape::Point) {   // a luminaire: no triangles (a camera sees its opening)
    scene.lights.push_back(ImportedLight{given.label(), cell, Parallelogram{given.corner, given.edge1, given.edge2},
                                         given.radiance, given.shape, given.intensity, given.opening});
    return;
  }
  ImportedObject object;
  object.label = given.label();
  object.cell = cell;
  const Vec3 a = given.corner, b = given.corner + given.edge1, c = given.corner + given.edge2;
  if (given.shape == LightShape::Triangle) {
    object.positions = {a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z};
    object.indices = {0, 1, 2};
  } else {
    const Vec3 d = given.corner + given.edge1 + given.edge2;
    object.positions = {a.x, a.y, a.z, b.x, b.y, b.z, d.x, d.y, d.z, c.x, c.y, c.z};
    object.indices = {0, 1, 2, 0, 2, 3};   // both wound like cross(edge1, edge2)
  }
  object.material = materials.add(given.name, Vec3(0.0f), given.radiance, scene.materials);
  scene.lights.push_back(ImportedLight{given.label(), cell, Parallelogram{given.corner, given.edge1, given.edge2},
                                       given.radiance, given.shape});
  scene.objects.push_back(std::move(object));
}

// The area of every triangle of a mesh file (m^2).
double meshArea(const LoadedMeshFile& mesh) {
  double area = 0;
  for (const MeshFilePart& part : mesh.parts) {
    const auto vertex = [&](uint32_t i) {
      return Vec3(part.positions[3 * i], part.positions[3 * i + 1], part.positions[3 * i + 2]);
    };
    for (size_t t = 0; t + 2 < part.indices.size(); t += 3) {
      const Vec3 a = vertex(part.indices[t]), b = vertex(part.indices[t + 1]), c = vertex(part.indices[t + 2]);
      area += 0.5 * double(length(cross(b - a, c - a)));
    }
  }
  return area;
}

// An object's emission: "emission" as given, or its "lumens" spread over
// the mesh file's whole area.
std::optional<Vec3> objectEmission(const BuildingObject& entry, const LoadedMeshFile& mesh) {
  if (!entry.lumens) return entry.emission;
  const double area = meshArea(mesh);
  if (!(area > 0)) throw std::runtime_error(fmt::format("{}: \"lumens\" needs triangles of nonzero area", entry.label()));
  return radianceOfLumens(entry.lumens->lumens, entry.lumens->colour, area);
}

const Bounds3& findCellBounds(const BuildingDescription& building, const std::string& name) {
  for (const BuildingCell& cell : *building.cells)
    if (cell.name == name) return cell.bounds;
  throw std::logic_error("unknown cell " + name);   // readBuildingJson checked every name
}

// `imageDirectory`: where images embedded in mesh files are written.
ImportedScene sceneFromBuildingJson(const std::string& path, const ImportOptions& options,
                                    const std::string& imageDirectory) {
  const BuildingDescription building = readBuildingJson(path);
  auto fail = [&](const std::string& problem) {
    throw std::runtime_error(fmt::format("{}: {}", path, problem));
  };
  const BuildingCamera& chosen = chooseCamera(building, options.camera);
  const bool givenCells = building.cells.has_value();
  const bool checkCells = givenCells && options.gridResolution == 0;

  ImportedScene scene;
  std::map<std::string, uint32_t> cellIds;
  if (givenCells) {
    for (const BuildingCell& cell : *building.cells) {
      cellIds[cell.name] = static_cast<uint32_t>(scene.cells.size());
      scene.cells.push_back(ImportedCell{cell.name, cell.bounds});
    }
  } else {
    scene.cells.push_back(ImportedCell{kSingleCellName, Bounds3()});   // bounds once the meshes are read
  }
  for (const BuildingPortal& portal : building.portals)
    scene.portals.push_back(ImportedPortal{cellIds.at(portal.cellA), cellIds.at(portal.cellB), portal.polygon});

  MaterialTable materials;
  for (const BuildingObject& entry : building.objects) {
    LoadedMeshFile mesh;
    try {
      mesh = loadMeshFile(entry.meshPath, imageDirectory);
    } catch (const std::runtime_error& e) {
      fail(fmt::format("{}: {}", entry.label(), e.what()));
    }
    scene.degenerateTrianglesDropped += mesh.degenerateTriangles;
    const uint32_t cell = givenCells ? cellIds.at(entry.cell) : 0;
    std::optional<Vec3> emission;
    try {
      emission = objectEmission(entry, mesh);
    } catch (const std::runtime_error& e) {
      fail(e.what());
    }
    if (entry.glass) {
      ImportedObject object;
      object.label = entry.label();
      object.cell = cell;
      for (const MeshFilePart& part : mesh.parts) appendPart(part, object);
      object.material = materials.add(entry.name, Vec3(0.0f), Vec3(0.0f), scene.materials, std::string(), entry.glass->transmittance,
                                      entry.glass->ior);
      scene.objects.push_back(std::move(object));
    } else if (!entry.albedo) {
      try {
        addPartsWithFileMaterials(mesh, entry.label(), cell, emission, materials, scene);
      } catch (const std::runtime_error& e) {
        fail(e.what());
      }
    } else {
      ImportedObject object;
      object.label = entry.label();
      object.cell = cell;
      for (const MeshFilePart& part : mesh.parts) appendPart(part, object);
      const Vec3 radiance = emission.value_or(Vec3(0.0f));
      object.material = materials.add(entry.name, *entry.albedo, radiance, scene.materials);
      if (maxComponent(radiance) > 0.0f) addEmitter(object, radiance, scene);
      scene.objects.push_back(std::move(object));
    }
    if (options.onMeshRead) options.onMeshRead(scene.objects.size(), building.objects.size());
  }

  for (const BuildingLight& light : building.lights)
    addGivenLight(light, givenCells ? cellIds.at(light.cell) : 0, materials, scene);

  for (const ImportedObject& object : scene.objects) extendBounds(scene.bounds, object);
  for (const BuildingCamera& camera : building.cameras) scene.bounds.extend(camera.camera.origin);
  for (const ImportedLight& light : scene.lights)   // a luminaire's opening, which cameras see
    if (const Bounds3 opening = light.areaLight().openingBounds(); !opening.empty()) scene.bounds.extend(opening);
  for (const BuildingLight& light : building.lights) {
    if (light.shape != LightShape::Point) continue;   // area lights' triangles are objects
    scene.bounds.extend(light.corner);
    if (checkCells && !findCellBounds(building, light.cell).contains(light.corner))
      fail(fmt::format("{}: position {} lies outside the aabb of its cell '{}'", light.label(), formatVec(light.corner),
                       light.cell));
  }
  for (const ImportedCell& cell : scene.cells)
    if (!cell.bounds.empty()) scene.bounds.extend(cell.bounds);
  if (!givenCells) scene.cells[0].bounds = padded(scene.bounds);

  if (checkCells) checkObjectsInCells(scene, path);
  // Every camera is stored under its name, the chosen one first (the
  // store's default).
  scene.cameras.push_back(chosen.camera);
  for (const BuildingCamera& camera : building.cameras)
    if (&camera != &chosen) scene.cameras.push_back(camera.camera);
  for (Camera& camera : scene.cameras) {
    const std::optional<uint32_t> cell = options.gridResolution > 0
                                             ? std::optional<uint32_t>(0)
                                             : smallestCellContaining(scene.cells, camera.origin);
    if (!cell)
      fail(fmt::format("camera '{}': origin {} lies outside every cell; move it into a cell or add a cell around it",
                       camera.name, formatVec(camera.origin)));
    camera.cell = *cell;
  }
  scene.site = building.site;
  return scene;
}

ImportedScene sceneFromMeshFiles(const std::vector<std::string>& paths, const std::string& imageDirectory) {
  ImportedScene scene;
  MaterialTable materials;
  for (const std::string& path : paths) {
    const LoadedMeshFile mesh = loadMeshFile(path, imageDirectory);
    scene.degenerateTrianglesDropped += mesh.degenerateTriangles;
    addPartsWithFileMaterials(mesh, fmt::format("mesh file '{}'", path), 0, std::nullopt, materials, scene);
  }
  for (const ImportedObject& object : scene.objects) extendBounds(scene.bounds, object);
  scene.cells.push_back(ImportedCell{kSingleCellName, padded(scene.bounds)});
  // A default view: from the middle of everything, looking down -z.
  Camera& camera = scene.cameras.emplace_back();
  camera.origin = scene.bounds.center();
  camera.target = camera.origin - Vec3(0.0f, 0.0f, 1.0f);
  camera.up = Vec3(0.0f, 1.0f, 0.0f);
  camera.fovYDegrees = 60.0f;
  camera.width = 512;
  camera.height = 384;
  camera.cell = 0;
  return scene;
}

void writeGivenCells(const ImportedScene& scene, SceneStoreWriter& writer) {
  for (const ImportedPortal& portal : scene.portals) writer.addPortal(portal.cellA, portal.cellB, portal.polygon);
  for (const ImportedLight& light : scene.lights) writer.addLight(light.areaLight());
  writer.setCamera(scene.cameras.front());
  for (size_t k = 1; k < scene.cameras.size(); ++k) writer.addCamera(scene.cameras[k]);
  // One output cell in memory at a time.
  for (uint32_t id = 0; id < scene.cells.size(); ++id) {
    CellContent cell;
    cell.id = id;
    cell.name = scene.cells[id].name;
    cell.bounds = scene.cells[id].bounds;
    bool textured = false;
    for (const ImportedObject& object : scene.objects) {
      if (object.cell != id) continue;
      const auto offset = static_cast<uint32_t>(cell.positions.size() / 3);
      cell.positions.insert(cell.positions.end(), object.positions.begin(), object.positions.end());
      for (uint32_t index : object.indices) cell.indices.push_back(offset + index);
      cell.materials.insert(cell.materials.end(), object.triangleCount(), object.material);
      // uvs for every vertex of the cell (zeros for untextured objects), or none.
      textured = textured || !object.uvs.empty();
      if (object.uvs.empty())
        cell.uvs.insert(cell.uvs.end(), 2 * (object.positions.size() / 3), 0.0f);
      else
        cell.uvs.insert(cell.uvs.end(), object.uvs.begin(), object.uvs.end());
    }
    if (!textured) cell.uvs.clear();
    writer.writeCell(cell);
  }
}

}  // namespace

ImportSummary importBuilding(const std::vector<std::string>& inputs, const std::string& storeDirectory,
                             const ImportOptions& options) {
  if (inputs.empty()) throw std::runtime_error("scene import: no input (a building.json, or mesh files)");
  if (options.gridResolution > kMaxImportGridResolution)
    throw std::runtime_error(fmt::format("scene import: --grid {} is above the maximum of {}", options.gridResolution,
                                         kMaxImportGridResolution));
  const bool building = isBuildingJson(inputs.front());
  for (const std::string& input : inputs)
    if (isBuildingJson(input) && inputs.size() > 1)
      throw std::runtime_error(fmt::format(
          "scene import: {} is a building.json; it must be the only input (it names its own meshes)", input));
  if (!building && !options.camera.empty())
    throw std::runtime_error("scene import: a camera name needs a building.json with \"cameras\"");

  // A scene store as input: re-cut a generated or imported building (--grid).
  const bool store = inputs.size() == 1 && isSceneStore(inputs.front());
  if (options.findRooms && options.gridResolution > 0)
    throw std::runtime_error("scene import: --cells rooms and --grid are alternatives; give one");
  if (store && options.gridResolution == 0 && !options.findRooms)
    throw std::runtime_error(fmt::format("scene import: {} is already a scene store; give --grid RG to re-cut it "
                                         "into uniform cells", inputs.front()));
  // Images embedded in mesh files wait here until the store copies them.
  const TemporaryDirectory embeddedImages("portico-import-images");
  const std::string imageDirectory = embeddedImages.path().string();
  ImportedScene scene = store      ? sceneFromStore(inputs.front())
                              : building ? sceneFromBuildingJson(inputs.front(), options, imageDirectory)
                                         : sceneFromMeshFiles(inputs, imageDirectory);

  // The rooms are found before the store is created: a mesh without rooms leaves nothing behind.
  std::optional<FoundRooms> rooms;
  if (options.findRooms) {
    std::string source = inputs.front();
    for (size_t k = 1; k < inputs.size(); ++k) source += ", " + inputs[k];
    rooms = findRooms(scene, source, options.rooms);
    if (options.onRoomsFound) options.onRoomsFound(rooms->rooms, rooms->cells.size(), rooms->portals.size());
    if (options.lampPerFoundRoom) addRoomLamps(*rooms, scene);
    if (options.cameraPerFoundRoom) addRoomCameras(*rooms, !options.camera.empty(), scene);
  }

  nlohmann::json sources = nlohmann::json::array();
  for (const std::string& input : inputs) sources.push_back(fs::absolute(input).lexically_normal().string());
  SceneStoreWriter writer(storeDirectory);
  writer.setMeta("generator", "import");
  writer.setMeta("source", sources.dump());
  writer.setMeta("degenerate_triangles_dropped", std::to_string(scene.degenerateTrianglesDropped));
  writer.setMeta("cells",
                 options.gridResolution > 0
                     ? fmt::format("grid {}^3", options.gridResolution)
                     : rooms ? fmt::format("rooms found: {} rooms, {} m voxels", rooms->rooms, rooms->voxelSize)
                     : (scene.cells.size() == 1 && scene.portals.empty() ? "one cell" : "given"));
  if (scene.site) writer.setSite(*scene.site);
  for (const ImportedMaterial& material : scene.materials) {
    const uint32_t id = writer.addMaterial(material.name, material.albedo, material.emission, material.hiddenFromCamera);
    if (!material.albedoTexture.empty()) writer.setMaterialTexture(id, material.albedoTexture);
    if (maxComponent(material.transmittance) > 0.0f) writer.setMaterialGlass(id, material.transmittance, material.ior);
  }
  if (rooms)
    writeRoomCells(scene, *rooms, writer);
  else if (options.gridResolution > 0)
    writeVoxelCells(scene, VoxelGrid(padded(scene.bounds), options.gridResolution), writer);
  else
    writeGivenCells(scene, writer);
  writer.commit();
  ImportSummary summary;
  summary.triangles = scene.triangleCount();
  summary.degenerateTrianglesDropped = scene.degenerateTrianglesDropped;
  summary.lights = scene.lights.size();
  if (rooms) {
    summary.rooms = rooms->roomAir;
    summary.shelteredAir = rooms->shelteredAir;
    summary.roomCells = rooms->cells.size();
    summary.roomPortals = rooms->portals.size();
    summary.roomVoxelSize = rooms->voxelSize;
  }
  if (scene.lights.empty()) summary.warnings.push_back(kNoLightsWarning);
  return summary;
}

}  // namespace portico
