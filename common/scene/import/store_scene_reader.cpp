#include "common/scene/import/store_scene_reader.h"

#include <filesystem>
#include <map>

#include "common/scene/store/cell_geometry.h"
#include "common/scene/store/scene_store.h"

namespace portico {

bool isSceneStore(const std::string& path) {
  std::error_code error;
  return std::filesystem::is_regular_file(std::filesystem::path(path) / "scene.db", error);
}

ImportedScene sceneFromStore(const std::string& directory) {
  const SceneStore store = SceneStore::open(directory);
  ImportedScene scene;
  for (const Material& m : store.materials())
    scene.materials.push_back(ImportedMaterial{m.name, m.albedo, m.emission, m.hiddenFromCamera,
                                               m.textured() ? directory + "/" + m.albedoTexture : std::string(),
                                               m.transmittance, m.ior});
  for (const CellInfo& info : store.cells()) {
    scene.cells.push_back(ImportedCell{info.name, info.bounds});
    scene.bounds.extend(info.bounds);
    const auto geometry = CellGeometry::load(store.cellPath(info.id), info.id, store.materials().size());
    const MeshView& mesh = geometry->mesh();
    // Triangles grouped by material, each group one object with its own vertices.
    std::map<uint32_t, ImportedObject> byMaterial;
    for (uint32_t t = 0; t < mesh.triangleCount; ++t) {
      ImportedObject& object = byMaterial[geometry->material(t)];
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = mesh.indices[3 * size_t(t) + k];
        object.positions.insert(object.positions.end(), {mesh.positions[3 * size_t(v)], mesh.positions[3 * size_t(v) + 1],
                                                         mesh.positions[3 * size_t(v) + 2]});
        object.indices.push_back(uint32_t(object.positions.size() / 3 - 1));
        if (geometry->uvs() && store.materials()[geometry->material(t)].textured())
          object.uvs.insert(object.uvs.end(), {geometry->uvs()[2 * size_t(v)], geometry->uvs()[2 * size_t(v) + 1]});
      }
    }
    for (auto& [material, object] : byMaterial) {
      object.label = info.name + "/" + store.materials()[material].name;
      object.cell = info.id;
      object.material = material;
      scene.objects.push_back(std::move(object));
    }
  }
  for (const Portal& portal : store.portals()) scene.portals.push_back(ImportedPortal{portal.cellA, portal.cellB, portal.polygon});
  for (const AreaLight& light : store.lights())
    scene.lights.push_back(ImportedLight{"light " + std::to_string(light.id), light.cell,
                                         Parallelogram{light.corner, light.edge1, light.edge2}, light.radiance,
                                         light.shape, light.intensity, light.opening});
  scene.cameras = store.cameras();
  scene.site = store.site();
  for (const Camera& camera : scene.cameras) scene.bounds.extend(Bounds3(camera.origin, camera.origin));
  return scene;
}

}  // namespace portico
