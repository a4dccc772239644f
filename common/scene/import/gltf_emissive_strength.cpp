#include "common/scene/import/gltf_emissive_strength.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

namespace portico {

namespace {

std::string lowerExtension(const std::string& path) {
  std::string extension = std::filesystem::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

// The JSON chunk of a GLB: 12-byte header, then chunk 0 (length, "JSON").
std::string glbJson(const std::string& bytes) {
  if (bytes.size() < 20 || bytes.compare(0, 4, "glTF") != 0) return {};
  uint32_t length = 0, type = 0;
  std::memcpy(&length, bytes.data() + 12, 4);
  std::memcpy(&type, bytes.data() + 16, 4);
  if (type != 0x4E4F534Au || length > bytes.size() - 20) return {};
  return bytes.substr(20, length);
}

}  // namespace

float GltfEmissiveStrengths::of(const std::string& name, size_t assimpIndex) const {
  if (std::count(names.begin(), names.end(), name) == 1)
    return strengths[size_t(std::find(names.begin(), names.end(), name) - names.begin())];
  return assimpIndex < strengths.size() ? strengths[assimpIndex] : 1.0f;
}

GltfEmissiveStrengths gltfEmissiveStrengths(const std::string& path) {
  const std::string extension = lowerExtension(path);
  if (extension != ".gltf" && extension != ".glb") return {};
  std::ifstream in(path, std::ios::binary);
  const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  const nlohmann::json document =
      nlohmann::json::parse(extension == ".glb" ? glbJson(bytes) : bytes, nullptr, /*allow_exceptions=*/false);
  if (!document.is_object() || !document.contains("materials") || !document["materials"].is_array()) return {};
  GltfEmissiveStrengths result;
  for (const nlohmann::json& material : document["materials"]) {
    float strength = 1.0f;
    const nlohmann::json* value = nullptr;
    if (material.is_object() && material.contains("extensions") && material["extensions"].is_object() &&
        material["extensions"].contains("KHR_materials_emissive_strength")) {
      const nlohmann::json& extension = material["extensions"]["KHR_materials_emissive_strength"];
      if (extension.is_object() && extension.contains("emissiveStrength")) value = &extension["emissiveStrength"];
    }
    if (value != nullptr && value->is_number() && value->get<double>() >= 0.0)
      strength = static_cast<float>(value->get<double>());
    result.strengths.push_back(strength);
    result.names.push_back(material.is_object() && material.contains("name") && material["name"].is_string()
                               ? material["name"].get<std::string>()
                               : std::string());
  }
  return result;
}

}  // namespace portico
