// Assimp -> MeshFilePart lists: walks the node tree, applies each node's
// accumulated transform, keeps triangles with their winding.
#include "common/scene/import/mesh_loader.h"

#include <assimp/Importer.hpp>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <filesystem>
#include <stdexcept>

#include "common/scene/import/gltf_emissive_strength.h"

namespace portico {

namespace {

// Assimp's messages may span lines; ours are one line.
std::string oneLine(std::string text) {
  std::replace(text.begin(), text.end(), '\n', ' ');
  std::replace(text.begin(), text.end(), '\r', ' ');
  while (!text.empty() && text.back() == ' ') text.pop_back();
  return text;
}

[[noreturn]] void fail(const std::string& path, const std::string& problem) {
  throw std::runtime_error(fmt::format("mesh file '{}': {}", path, problem));
}

// Writes an image embedded in the mesh file (GLB; a compressed PNG or JPEG
// file's bytes) into `directory`, returning its path; empty when there is no
// directory to write to or the image is stored as raw texels.
std::string extractEmbeddedImage(const aiTexture& image, const std::string& meshPath, const std::string& directory,
                                 unsigned index) {
  if (directory.empty() || image.mHeight != 0 || image.pcData == nullptr) return {};
  std::string hint(image.achFormatHint, strnlen(image.achFormatHint, sizeof image.achFormatHint));
  if (hint.empty()) hint = "img";
  const std::string path = fmt::format("{}/{:016x}-{}.{}", directory, std::hash<std::string>()(meshPath), index, hint);
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(image.pcData), std::streamsize(image.mWidth));
  if (!out) fail(meshPath, fmt::format("cannot write its embedded image {} to {}", index, path));
  return path;
}

// The material's colour image: glTF's base colour texture, else the
// classic diffuse one (OBJ map_Kd), resolved against the mesh file's folder
// (backslashes of files written on Windows read as slashes), or an image
// embedded in the file ("*N" in a GLB) written into `embeddedImageDirectory`.
// Empty when it has none.
std::string diffuseTexture(const aiScene& scene, const aiMaterial& source, const std::string& meshPath,
                           const std::string& materialName, const std::string& embeddedImageDirectory) {
  aiString raw;
  if (source.GetTexture(aiTextureType_BASE_COLOR, 0, &raw) != aiReturn_SUCCESS &&
      source.GetTexture(aiTextureType_DIFFUSE, 0, &raw) != aiReturn_SUCCESS)
    return {};
  std::string name = raw.C_Str();
  if (name.empty()) return {};
  if (const auto [embedded, index] = scene.GetEmbeddedTextureAndIndex(name.c_str()); embedded)
    return extractEmbeddedImage(*embedded, meshPath, embeddedImageDirectory, static_cast<unsigned>(index));
  if (name[0] == '*') return {};
  std::replace(name.begin(), name.end(), '\\', '/');
  const std::filesystem::path given(name);
  const std::filesystem::path resolved =
      given.is_absolute() ? given : std::filesystem::path(meshPath).parent_path() / given;
  std::error_code error;
  if (!std::filesystem::is_regular_file(resolved, error))
    fail(meshPath, fmt::format("material '{}': texture '{}' ({}) does not exist; put the image there, or remove the "
                               "texture from the material to use its colour",
                               materialName, name, resolved.lexically_normal().string()));
  return resolved.lexically_normal().string();
}

// `fileStrength`: the material's KHR_materials_emissive_strength as the file
// gives it, applied where Assimp does not report an intensity itself.
MeshFileMaterial readMaterial(const aiScene& scene, const aiMaterial& source, size_t index, float fileStrength,
                              const std::string& path, const std::string& embeddedImageDirectory) {
  MeshFileMaterial material;
  aiString name;
  material.name = source.Get(AI_MATKEY_NAME, name) == aiReturn_SUCCESS && name.length > 0
                      ? std::string(name.C_Str())
                      : fmt::format("material-{}", index);
  aiColor4D colour;
  // glTF's base colour when present (Assimp also maps it to the diffuse
  // colour, but not for every version), otherwise the classic diffuse colour.
  if (source.Get(AI_MATKEY_BASE_COLOR, colour) == aiReturn_SUCCESS ||
      source.Get(AI_MATKEY_COLOR_DIFFUSE, colour) == aiReturn_SUCCESS)
    material.diffuse = Vec3(colour.r, colour.g, colour.b);
  if (source.Get(AI_MATKEY_COLOR_EMISSIVE, colour) == aiReturn_SUCCESS) {
    material.emissive = Vec3(colour.r, colour.g, colour.b);
    float strength = fileStrength;   // KHR_materials_emissive_strength
    source.Get(AI_MATKEY_EMISSIVE_INTENSITY, strength);
    material.emissive *= strength;
  }
  material.diffuseTexture = diffuseTexture(scene, source, path, material.name, embeddedImageDirectory);
  // Transparency: glTF's transmission tints by the base colour; an MTL's
  // dissolve (Assimp's opacity; Tr is read as 1 - d) by its Tf colour.
  float transmission = 0, opacity = 1;
  if (source.Get(AI_MATKEY_TRANSMISSION_FACTOR, transmission) == aiReturn_SUCCESS && transmission > 0) {
    material.transmittance = material.diffuse * std::min(transmission, 1.0f);
  } else if (source.Get(AI_MATKEY_OPACITY, opacity) == aiReturn_SUCCESS && opacity < 1.0f) {
    aiColor3D filter(1, 1, 1);
    source.Get(AI_MATKEY_COLOR_TRANSPARENT, filter);
    if (!(filter.r > 0 || filter.g > 0 || filter.b > 0)) filter = aiColor3D(1, 1, 1);
    material.transmittance = Vec3(filter.r, filter.g, filter.b) * (1.0f - std::max(opacity, 0.0f));
  }
  return material;
}

// Zero area: a repeated corner, or corners on one line so exactly that the
// cross product of the edges is zero in float. Such a triangle has no normal
// (normalising gives NaN) and can never be hit, so it is dropped.
bool isDegenerate(const std::vector<float>& positions, uint32_t a, uint32_t b, uint32_t c) {
  if (a == b || b == c || a == c) return true;
  const auto at = [&](uint32_t i) {
    const float* p = &positions[3 * size_t{i}];
    return Vec3(p[0], p[1], p[2]);
  };
  return !(length(cross(at(b) - at(a), at(c) - at(a))) > 0.0f);
}

class PartCollector {
 public:
  PartCollector(const aiScene& scene, LoadedMeshFile& file) : scene_(scene), file_(file) {}

  void visit(const aiNode& node, const aiMatrix4x4& parentTransform, const std::string& parentPath) {
    const aiMatrix4x4 transform = parentTransform * node.mTransformation;
    const std::string path = parentPath.empty() ? std::string(node.mName.C_Str())
                                                : parentPath + "/" + node.mName.C_Str();
    for (unsigned i = 0; i < node.mNumMeshes; ++i) addPart(*scene_.mMeshes[node.mMeshes[i]], transform, path);
    for (unsigned i = 0; i < node.mNumChildren; ++i) visit(*node.mChildren[i], transform, path);
  }

 private:
  void addPart(const aiMesh& mesh, const aiMatrix4x4& transform, const std::string& nodePath) {
    MeshFilePart part;
    part.name = mesh.mName.length > 0 ? fmt::format("{}/{}", nodePath, mesh.mName.C_Str()) : nodePath;
    part.material = mesh.mMaterialIndex < file_.materials.size() ? mesh.mMaterialIndex : 0;
    // A mirroring transform turns the winding around; swap two corners so
    // the front stays the side the author meant (glTF 2.0, section 3.7.4).
    const bool mirrors = transform.Determinant() < 0;
    part.positions.reserve(3 * size_t{mesh.mNumVertices});
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D& raw = mesh.mVertices[v];
      if (!isFinite(Vec3(raw.x, raw.y, raw.z)))
        fail(file_.path,
             fmt::format("part '{}': vertex {} is not finite ({}, {}, {})", part.name, v, raw.x, raw.y, raw.z));
      const aiVector3D p = transform * raw;
      if (!isFinite(Vec3(p.x, p.y, p.z)))
        fail(file_.path,
             fmt::format("part '{}': vertex {} is not finite once placed by its node transforms", part.name, v));
      part.positions.insert(part.positions.end(), {p.x, p.y, p.z});
    }
    // Texture coordinates only where the part's material has a texture:
    // untextured cells store none.
    if (mesh.HasTextureCoords(0) && !file_.materials[part.material].diffuseTexture.empty()) {
      part.uvs.reserve(2 * size_t{mesh.mNumVertices});
      for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
        const aiVector3D& uv = mesh.mTextureCoords[0][v];
        if (!std::isfinite(uv.x) || !std::isfinite(uv.y))
          fail(file_.path, fmt::format("part '{}': vertex {}'s texture coordinate is not finite", part.name, v));
        part.uvs.insert(part.uvs.end(), {uv.x, uv.y});
      }
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;   // points and lines
      const uint32_t a = face.mIndices[0], b = face.mIndices[1], c = face.mIndices[2];
      if (std::max({a, b, c}) >= mesh.mNumVertices)
        fail(file_.path, fmt::format("part '{}': face {} uses vertex {}, but the part has {} vertices", part.name, f,
                                     std::max({a, b, c}), mesh.mNumVertices));
      if (isDegenerate(part.positions, a, b, c)) {
        ++file_.degenerateTriangles;
        continue;
      }
      if (mirrors)
        part.indices.insert(part.indices.end(), {a, c, b});
      else
        part.indices.insert(part.indices.end(), {a, b, c});
    }
    if (!part.indices.empty()) file_.parts.push_back(std::move(part));
  }

  const aiScene& scene_;
  LoadedMeshFile& file_;
};

}  // namespace

size_t LoadedMeshFile::triangleCount() const {
  size_t count = 0;
  for (const MeshFilePart& part : parts) count += part.triangleCount();
  return count;
}

LoadedMeshFile loadMeshFile(const std::string& path, const std::string& embeddedImageDirectory) {
  std::error_code error;
  if (!std::filesystem::exists(path, error)) fail(path, "does not exist");
  if (!std::filesystem::is_regular_file(path, error)) fail(path, "is not a regular file");

  Assimp::Importer importer;
  // Only what every format needs: polygons to triangles, shared vertices.
  // Deliberately absent: winding flips, left-handed conversion, generated or
  // fixed normals, Assimp's degenerate removal (it would turn some triangles
  // into lines and points silently; PartCollector drops and counts them).
  const aiScene* scene = importer.ReadFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices);
  if (scene == nullptr) fail(path, fmt::format("cannot be read: {}", oneLine(importer.GetErrorString())));
  if (scene->mRootNode == nullptr) fail(path, "cannot be read: the file has no scene");

  LoadedMeshFile file;
  file.path = path;
  const GltfEmissiveStrengths strengths = gltfEmissiveStrengths(path);
  for (unsigned m = 0; m < scene->mNumMaterials; ++m) {
    aiString name;
    scene->mMaterials[m]->Get(AI_MATKEY_NAME, name);
    file.materials.push_back(
        readMaterial(*scene, *scene->mMaterials[m], m, strengths.of(name.C_Str(), m), path, embeddedImageDirectory));
  }
  if (file.materials.empty()) file.materials.push_back(MeshFileMaterial{"default"});
  PartCollector(*scene, file).visit(*scene->mRootNode, aiMatrix4x4(), "");
  if (file.parts.empty())
    fail(path, file.degenerateTriangles > 0
                   ? fmt::format("has no triangles but {} degenerate (zero-area) ones", file.degenerateTriangles)
                   : std::string("has no triangles"));
  return file;
}

}  // namespace portico
