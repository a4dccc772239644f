// KHR_materials_emissive_strength of a glTF file, read from its JSON: the
// Assimp of Debian 12 (5.2) drops the extension, so a glTF lamp brighter
// than emissiveFactor's [0, 1] would import as a dim one.
#pragma once

#include <string>
#include <vector>

namespace portico {

struct GltfEmissiveStrengths {
  // Per entry of the file's "materials": its "name" ("" if none) and
  // factor (1 where the extension is absent).
  std::vector<std::string> names;
  std::vector<float> strengths;
  // The factor of the material Assimp calls `name`, its `assimpIndex`-th:
  // matched by name where the file names it once (Assimp numbers glTF
  // materials in the order meshes first use them, not the file's), else by
  // index; 1 when neither matches.
  float of(const std::string& name, size_t assimpIndex) const;
};

// Empty when `path` is not a .gltf/.glb or its JSON cannot be read (the
// mesh loader reports unreadable files itself).
GltfEmissiveStrengths gltfEmissiveStrengths(const std::string& path);

}  // namespace portico
