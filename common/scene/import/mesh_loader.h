// Loads a mesh file (OBJ, PLY, glTF/GLB and whatever else Assimp reads) into
// plain triangle lists in world coordinates, for the building importer.
//
// Conventions kept from the file, never changed by the loader:
//  * Winding. Assimp is asked only to triangulate polygons and join identical
//    vertices; nothing flips or reorders triangles and no normals are made.
//    A triangle's front is the side of cross(v1 - v0, v2 - v0) (flat normals
//    from the winding, as in the scene store). One exception, as glTF
//    specifies: a node transform that mirrors (negative determinant) would
//    turn the front to the back, so such instances get two indices swapped.
//  * Units and axes. Positions are used as they are: metres, right-handed,
//    +Y up. Node transforms (glTF hierarchies, a Collada up-axis fix) are
//    applied.
// Points and lines are dropped, and so are degenerate (zero-area) triangles,
// counted; a file with no triangle left is an error.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/math.h"

namespace portico {

// A material as the mesh file declares it (colours straight from Assimp).
struct MeshFileMaterial {
  std::string name;
  Vec3 diffuse{0.8f, 0.8f, 0.8f};   // base colour (glTF) or diffuse colour (OBJ/MTL, PLY, ...)
  Vec3 emissive{0.0f};              // emissive colour times strength, where the format has one
  // The diffuse (OBJ/MTL map_Kd) or base colour (glTF baseColorTexture)
  // image, resolved against the mesh file's folder; empty when none. The
  // albedo is this image times `diffuse`.
  std::string diffuseTexture;
  // Light let through (thin glass when above 0): MTL (1 - d) or Tr times
  // Tf, glTF KHR_materials_transmission's factor times the base colour.
  Vec3 transmittance{0.0f};
};

// One placed mesh of the file: an Assimp mesh under one node, transformed.
struct MeshFilePart {
  std::string name;        // "<node>/<mesh>", for messages
  uint32_t material = 0;   // index into LoadedMeshFile::materials
  std::vector<float> positions;     // xyz per vertex, world space
  std::vector<uint32_t> indices;    // 3 per triangle
  std::vector<float> uvs;           // uv per vertex (the first set), or empty: the mesh has none
  size_t triangleCount() const { return indices.size() / 3; }
};

struct LoadedMeshFile {
  std::string path;
  std::vector<MeshFileMaterial> materials;
  std::vector<MeshFilePart> parts;   // only parts with at least one triangle
  // Zero-area triangles left out of `parts` (a repeated corner, or three
  // corners on one line): they have no normal and can never be hit.
  size_t degenerateTriangles = 0;
  size_t triangleCount() const;
};

// Throws std::runtime_error, one line naming the file: it does not exist, it
// cannot be read or parsed, it has no triangles, a vertex is not finite, or a
// material's texture file does not exist (naming the material and the path).
// Images embedded in the file (GLB) are written into embeddedImageDirectory
// and named by MeshFileMaterial::diffuseTexture; with no directory, or for
// an image stored as raw texels, the material keeps its colour.
LoadedMeshFile loadMeshFile(const std::string& path, const std::string& embeddedImageDirectory = {});

}  // namespace portico
