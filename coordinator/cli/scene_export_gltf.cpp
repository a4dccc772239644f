// glTF 2.0 writer of a scene store, written directly with nlohmann-json: the
// layout (one node per cell, lamps as primitives of their own, portals and
// light records as extras, the camera as a glTF camera) needs nothing of
// Assimp's exporter, which writes neither cameras nor extras the way a
// reader of portico stores wants them.
#include "coordinator/cli/scene_export_gltf.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <stdexcept>
#include <vector>

#include "common/scene/store/cell_geometry.h"
#include "common/scene/store/scene_store.h"
#include "coordinator/cli/export_groups.h"

namespace portico::cli {

namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr uint32_t kFloat = 5126, kUnsignedInt = 5125;
constexpr uint32_t kArrayBuffer = 34962, kElementArrayBuffer = 34963;

json vec3(const Vec3& v) { return json::array({v.x, v.y, v.z}); }

// The binary buffer and the accessors into it.
class BufferBuilder {
 public:
  explicit BufferBuilder(json& document) : document_(document) {}

  // Triangles `triangles` of `mesh` as unshared vertices (3 per triangle):
  // a POSITION accessor and an index accessor.
  json primitive(const MeshView& mesh, const std::vector<uint32_t>& triangles, uint32_t material,
                 ExportSummary& summary) {
    std::vector<float> positions;
    Bounds3 box;
    for (uint32_t t : triangles) {
      Vec3 v[3];
      mesh.triangle(t, v[0], v[1], v[2]);
      for (const Vec3& p : v) {
        positions.insert(positions.end(), {p.x, p.y, p.z});
        box.extend(p);
      }
    }
    std::vector<uint32_t> indices(positions.size() / 3);
    for (uint32_t i = 0; i < indices.size(); ++i) indices[i] = i;
    summary.triangles += triangles.size();
    summary.bounds.extend(box);
    const size_t positionView = view(positions.data(), positions.size() * sizeof(float), kArrayBuffer);
    const size_t indexView = view(indices.data(), indices.size() * sizeof(uint32_t), kElementArrayBuffer);
    json& accessors = document_["accessors"];
    accessors.push_back({{"bufferView", positionView}, {"componentType", kFloat}, {"count", indices.size()},
                         {"type", "VEC3"}, {"min", vec3(box.lo)}, {"max", vec3(box.hi)}});
    accessors.push_back(
        {{"bufferView", indexView}, {"componentType", kUnsignedInt}, {"count", indices.size()}, {"type", "SCALAR"}});
    return {{"attributes", {{"POSITION", accessors.size() - 2}}}, {"indices", accessors.size() - 1},
            {"material", material}};
  }

  const std::vector<uint8_t>& bytes() const { return bytes_; }

 private:
  size_t view(const void* data, size_t size, uint32_t target) {
    const size_t offset = bytes_.size();
    bytes_.resize(offset + size);
    std::memcpy(bytes_.data() + offset, data, size);
    bytes_.resize((bytes_.size() + 3) & ~size_t{3}, 0);   // every view starts 4-byte aligned
    document_["bufferViews"].push_back(
        {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", size}, {"target", target}});
    return document_["bufferViews"].size() - 1;
  }

  json& document_;
  std::vector<uint8_t> bytes_;
};

// Albedo as the base colour (not metallic, fully rough: Lambertian);
// radiance as emissiveFactor times KHR_materials_emissive_strength, since
// emissiveFactor alone stops at 1.
json materialOf(const Material& m, const std::string& name) {
  json material{{"name", name},
                {"pbrMetallicRoughness",
                 {{"baseColorFactor", {m.albedo.x, m.albedo.y, m.albedo.z, 1.0f}},
                  {"metallicFactor", 0.0f},
                  {"roughnessFactor", 1.0f}}},
                {"extras", {{"portico_material", m.id}, {"hidden_from_camera", m.hiddenFromCamera}}}};
  if (m.emissive()) {
    const float strength = std::max(1.0f, maxComponent(m.emission));
    material["emissiveFactor"] = vec3(m.emission * (1.0f / strength));
    if (strength > 1.0f) material["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"] = strength;
  }
  return material;
}

// A glTF camera looks along its node's -Z with +Y up.
json cameraNode(const Camera& camera, size_t cameraIndex) {
  const Vec3 back = normalize(camera.origin - camera.target);
  const Vec3 right = normalize(cross(camera.up, back));
  const Vec3 up = cross(back, right);
  json matrix = json::array();   // column-major
  for (const Vec3& column : {right, up, back}) matrix.insert(matrix.end(), {column.x, column.y, column.z, 0.0f});
  matrix.insert(matrix.end(), {camera.origin.x, camera.origin.y, camera.origin.z, 1.0f});
  return {{"name", "camera"},
          {"camera", cameraIndex},
          {"matrix", matrix},
          {"extras", {{"width", camera.width}, {"height", camera.height}, {"cell", camera.cell},
                      {"target", vec3(camera.target)}, {"up", vec3(camera.up)}}}};
}

json sceneExtras(const SceneStore& store) {
  json portals = json::array(), lights = json::array();
  for (const Portal& portal : store.portals()) {
    json polygon = json::array();
    for (const Vec3& p : portal.polygon) polygon.push_back(vec3(p));
    portals.push_back({{"cells", {store.cells()[portal.cellA].name, store.cells()[portal.cellB].name}},
                       {"polygon", polygon}});
  }
  for (const AreaLight& light : store.lights())
    lights.push_back({{"shape", light.isPoint() ? "point" : light.isTriangle() ? "triangle" : "parallelogram"},
                      {"cell", store.cells()[light.cell].name},
                      {"corner", vec3(light.corner)},
                      {"edge1", vec3(light.edge1)},
                      {"edge2", vec3(light.edge2)},
                      {"radiance", vec3(light.radiance)}});
  return {{"portico_store", store.directory()}, {"portico_portals", portals}, {"portico_lights", lights}};
}

void writeBytes(const std::string& path, const std::vector<uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  out.close();
  if (!out) throw std::runtime_error(fmt::format("{}: cannot be written", path));
}

void appendChunk(std::vector<uint8_t>& file, uint32_t type, std::vector<uint8_t> data, uint8_t padding) {
  data.resize((data.size() + 3) & ~size_t{3}, padding);
  const uint32_t header[2] = {static_cast<uint32_t>(data.size()), type};
  const auto* raw = reinterpret_cast<const uint8_t*>(header);
  file.insert(file.end(), raw, raw + sizeof(header));
  file.insert(file.end(), data.begin(), data.end());
}

// GLB: a 12-byte header, the JSON chunk (space-padded), the BIN chunk.
void writeGlb(const std::string& path, const json& document, const std::vector<uint8_t>& bin) {
  const std::string text = document.dump();
  std::vector<uint8_t> file(12);
  appendChunk(file, 0x4E4F534Au, std::vector<uint8_t>(text.begin(), text.end()), ' ');
  appendChunk(file, 0x004E4942u, bin, 0);
  const uint32_t header[3] = {0x46546C67u, 2u, static_cast<uint32_t>(file.size())};
  std::memcpy(file.data(), header, sizeof(header));
  writeBytes(path, file);
}

}  // namespace

bool isGltfPath(const std::string& path) {
  const std::string extension = fs::path(path).extension().string();
  return extension == ".glb" || extension == ".gltf";
}

ExportSummary exportStoreGltf(const std::string& directory, const std::string& path) {
  if (!isGltfPath(path)) throw std::runtime_error(fmt::format("{}: glTF export writes *.glb or *.gltf", path));
  const SceneStore store = SceneStore::open(directory);
  json document{{"asset", {{"version", "2.0"}, {"generator", "portico scene export"}}},
                {"scene", 0},
                {"bufferViews", json::array()},
                {"accessors", json::array()},
                {"meshes", json::array()},
                {"materials", json::array()},
                {"nodes", json::array()}};
  // Unique names: an importer matches the emissive strength by name.
  std::map<std::string, int> nameUses;
  for (const Material& m : store.materials()) ++nameUses[m.name];
  for (const Material& m : store.materials())
    document["materials"].push_back(materialOf(m, nameUses[m.name] > 1 ? fmt::format("{} #{}", m.name, m.id) : m.name));
  BufferBuilder buffer(document);
  ExportSummary summary;
  json sceneNodes = json::array();
  for (const CellInfo& cell : store.cells()) {
    const std::unique_ptr<CellGeometry> geometry =
        CellGeometry::load(store.cellPath(cell.id), cell.id, store.materials().size());
    json node{{"name", cell.name},
              {"extras", {{"portico_cell", cell.id}, {"min", vec3(cell.bounds.lo)}, {"max", vec3(cell.bounds.hi)}}}};
    json primitives = json::array();
    for (const TriangleGroup& group : exportGroups(*geometry, store.materials()))
      primitives.push_back(buffer.primitive(geometry->mesh(), group.triangles, group.material, summary));
    if (!primitives.empty()) {
      document["meshes"].push_back({{"name", cell.name}, {"primitives", primitives}});
      node["mesh"] = document["meshes"].size() - 1;
    }
    sceneNodes.push_back(document["nodes"].size());
    document["nodes"].push_back(node);
  }
  const Camera& camera = store.camera();
  document["cameras"] = {{{"type", "perspective"},
                          {"perspective",
                           {{"yfov", camera.fovYDegrees * kPi / 180.0f},
                            {"aspectRatio", float(camera.width) / float(camera.height)},
                            {"znear", 0.01f}}}}};
  sceneNodes.push_back(document["nodes"].size());
  document["nodes"].push_back(cameraNode(camera, 0));
  document["scenes"] = {{{"name", store.meta().count("name") ? store.meta().at("name") : std::string("building")},
                         {"nodes", sceneNodes},
                         {"extras", sceneExtras(store)}}};
  for (const json& material : document["materials"])
    if (material.contains("extensions")) document["extensionsUsed"] = {"KHR_materials_emissive_strength"};
  // glTF forbids empty top-level arrays (a store without triangles has no meshes).
  for (const char* key : {"bufferViews", "accessors", "meshes", "materials"})
    if (document[key].empty()) document.erase(key);
  json bufferEntry{{"byteLength", buffer.bytes().size()}};
  if (fs::path(path).extension() == ".glb") {
    document["buffers"] = json::array({bufferEntry});
    writeGlb(path, document, buffer.bytes());
  } else {
    const std::string binPath = fs::path(path).replace_extension(".bin").string();
    bufferEntry["uri"] = fs::path(binPath).filename().string();
    document["buffers"] = json::array({bufferEntry});
    writeBytes(binPath, buffer.bytes());
    const std::string text = document.dump(1);
    writeBytes(path, std::vector<uint8_t>(text.begin(), text.end()));
  }
  return summary;
}

}  // namespace portico::cli
