// Albedo textures: an OBJ's map_Kd imported into a store (uvs in the cell
// file, the image copied into textures/), looked up at texel centres through
// the texture module (orientation, repeat, sRGB), and the errors of a
// missing texture.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/image/png_file.h"
#include "common/scene/import/building_importer.h"
#include "common/scene/store/cell_geometry.h"
#include "common/scene/store/scene_store.h"
#include "common/transport/albedo_texture.h"
#include "tests/unit/scene/scene_test_support.h"

namespace portico {
namespace {

namespace fs = std::filesystem;
using testing_support::TempDirectory;

void writeText(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

template <typename Action>
std::string errorOf(Action&& action) {
  try {
    action();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

// 2 x 2 texels, row 0 at the top: red, green / blue, white (sRGB bytes).
const std::vector<uint8_t> kTexels = {200, 0, 0, 0, 150, 0,  /* top */ 0, 0, 100, 255, 255, 255 /* bottom */};

// A quad on y = 0 with uvs (0,0)..(1,1) and a map_Kd material (Kd 0.5, 1, 1),
// plus an untextured triangle of another material.
void writeTexturedObj(const fs::path& dir, const std::string& textureName = "tex.png") {
  writeText(dir / "quad.mtl", "newmtl painted\nKd 0.5 1 1\nmap_Kd " + textureName +
                                  "\nnewmtl plain\nKd 0.3 0.3 0.3\n");
  writeText(dir / "quad.obj",
            "mtllib quad.mtl\n"
            "v 0 0 0\nv 1 0 0\nv 1 0 -1\nv 0 0 -1\n"
            "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
            "usemtl painted\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n"
            "v 0 1 0\nv 1 1 0\nv 0 1 -1\n"
            "usemtl plain\nf 5 6 7\n");
}

TEST(Textures, AnObjMapKdBecomesAStoreTextureWithUvsInTheCellFile) {
  TempDirectory dir;
  writePng(dir / "tex.png", 2, 2, kTexels);
  writeTexturedObj(dir.path());
  importBuilding({dir / "quad.obj"}, dir / "store");

  const SceneStore store = SceneStore::open(dir / "store");
  const Material* painted = nullptr;
  for (const Material& m : store.materials()) {
    if (m.name == "painted") painted = &m;
    if (m.name == "plain") EXPECT_FALSE(m.textured());
  }
  ASSERT_NE(painted, nullptr);
  ASSERT_TRUE(painted->textured());
  EXPECT_EQ(painted->albedoTexture.rfind("textures/", 0), 0u) << painted->albedoTexture;
  EXPECT_TRUE(fs::is_regular_file(fs::path(store.directory()) / painted->albedoTexture));
  // The store is self-contained: the source image may go.
  fs::remove(dir / "tex.png");

  const auto cell = CellGeometry::load(store.cellPath(0), 0, store.materials().size());
  ASSERT_NE(cell->uvs(), nullptr);
  // Each corner of the painted quad keeps its uv; the plain triangle's are zeros.
  for (uint32_t t = 0; t < cell->mesh().triangleCount; ++t) {
    for (int corner = 0; corner < 3; ++corner) {
      const uint32_t v = cell->mesh().indices[3 * t + corner];
      const Vec3 p = cell->mesh().vertex(v);
      const float u = cell->uvs()[2 * v], w = cell->uvs()[2 * v + 1];
      if (store.materials()[cell->material(t)].textured()) {
        EXPECT_EQ(u, p.x);
        EXPECT_EQ(w, -p.z);
      } else {
        EXPECT_EQ(u, 0.0f);
        EXPECT_EQ(w, 0.0f);
      }
    }
  }
}

TEST(Textures, ACellWithoutTexturedTrianglesStoresNoUvs) {
  TempDirectory dir;
  writeText(dir / "plain.obj", "v 0 0 0\nv 1 0 0\nv 1 0 -1\nvt 0 0\nvt 1 0\nvt 1 1\nf 1/1 2/2 3/3\n");
  importBuilding({dir / "plain.obj"}, dir / "store");
  const SceneStore store = SceneStore::open(dir / "store");
  const auto cell = CellGeometry::load(store.cellPath(0), 0, store.materials().size());
  EXPECT_EQ(cell->uvs(), nullptr);
  EXPECT_FALSE(fs::exists(fs::path(store.directory()) / "textures"));
}

TEST(Textures, LookupsReadTexelCentresUprightRepeatingAndLinearised) {
  TempDirectory dir;
  writePng(dir / "tex.png", 2, 2, kTexels);
  writeTexturedObj(dir.path());
  importBuilding({dir / "quad.obj"}, dir / "store");
  const SceneStore store = SceneStore::open(dir / "store");
  const Material* painted = nullptr;
  for (const Material& m : store.materials())
    if (m.textured()) painted = &m;
  ASSERT_NE(painted, nullptr);
  AlbedoTextures& textures = AlbedoTextures::instance();
  const auto at = [&](float u, float v) { return textures.albedoAt(store.directory(), *painted, Uv{u, v}); };
  const auto expectNear = [](const Vec3& got, const Vec3& want) {
    EXPECT_NEAR(got.x, want.x, 1e-5f);
    EXPECT_NEAR(got.y, want.y, 1e-5f);
    EXPECT_NEAR(got.z, want.z, 1e-5f);
  };
  const Vec3 factor(0.5f, 1.0f, 1.0f);
  // v = 0.75 is the top row (v runs up), u = 0.25 the left column.
  expectNear(at(0.25f, 0.75f), Vec3(srgbToLinear(200 / 255.0f), 0, 0) * factor);
  expectNear(at(0.75f, 0.75f), Vec3(0, srgbToLinear(150 / 255.0f), 0) * factor);
  expectNear(at(0.25f, 0.25f), Vec3(0, 0, srgbToLinear(100 / 255.0f)) * factor);
  expectNear(at(0.75f, 0.25f), Vec3(1.0f) * factor);
  // Repeating: one period over is the same texel.
  expectNear(at(1.25f, -0.25f), at(0.25f, 0.75f));
  // Between texel centres: the average of linear values, not of bytes.
  const Vec3 middle = at(0.5f, 0.75f);
  EXPECT_NEAR(middle.x, 0.5f * srgbToLinear(200 / 255.0f) * 0.5f, 1e-5f);
  EXPECT_NEAR(middle.y, 0.5f * srgbToLinear(150 / 255.0f), 1e-5f);
  // A texture lookup never gives more than the factor allows.
  EXPECT_LE(maxComponent(at(0.9f, 0.1f)), 1.0f);
}

// A glTF quad on y = 0 whose corner (0, 0, 0) has glTF uv (0, 0), the
// image's top-left corner, and (1, 0, -1) uv (1, 1); base colour factor
// (0.5, 0.25, 1) times checker.png.
void writeTexturedGltf(const fs::path& dir) {
  const float positions[12] = {0, 0, 0, 1, 0, 0, 1, 0, -1, 0, 0, -1};
  const float uvs[8] = {0, 0, 1, 0, 1, 1, 0, 1};
  const uint16_t indices[6] = {0, 1, 2, 0, 2, 3};
  {
    std::ofstream bin(dir / "quad.bin", std::ios::binary);
    bin.write(reinterpret_cast<const char*>(positions), sizeof positions);
    bin.write(reinterpret_cast<const char*>(uvs), sizeof uvs);
    bin.write(reinterpret_cast<const char*>(indices), sizeof indices);
  }
  writeText(dir / "quad.gltf", R"({
  "asset": {"version": "2.0"},
  "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
  "materials": [{"name": "painted", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.25, 1, 1],
                 "baseColorTexture": {"index": 0}}}],
  "textures": [{"source": 0}], "images": [{"uri": "tex.png"}],
  "buffers": [{"uri": "quad.bin", "byteLength": 92}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 32},
                  {"buffer": 0, "byteOffset": 80, "byteLength": 12}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, -1], "max": [1, 0, 0]},
                {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
                {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}]
})");
}

TEST(Textures, AGltfBaseColorTextureIsReadTimesItsFactorWithVUpwards) {
  TempDirectory dir;
  writePng(dir / "tex.png", 2, 2, kTexels);
  writeTexturedGltf(dir.path());
  importBuilding({dir / "quad.gltf"}, dir / "store");
  const SceneStore store = SceneStore::open(dir / "store");
  ASSERT_EQ(store.materials().size(), 1u);
  const Material& painted = store.materials()[0];
  ASSERT_TRUE(painted.textured());
  EXPECT_NEAR(painted.albedo.x, 0.5f, 1e-6f);
  EXPECT_NEAR(painted.albedo.y, 0.25f, 1e-6f);
  const auto cell = CellGeometry::load(store.cellPath(0), 0, store.materials().size());
  ASSERT_NE(cell->uvs(), nullptr);
  // glTF's top-left (0, 0) is (0, 1) with v upwards: the red texel.
  for (uint32_t v = 0; v < cell->mesh().vertexCount; ++v) {
    const Vec3 p = cell->mesh().vertex(v);
    EXPECT_NEAR(cell->uvs()[2 * v], p.x, 1e-6f);
    EXPECT_NEAR(cell->uvs()[2 * v + 1], 1.0f + p.z, 1e-6f);
  }
  const Vec3 corner = AlbedoTextures::instance().albedoAt(store.directory(), painted, Uv{0.25f, 0.75f});
  EXPECT_NEAR(corner.x, srgbToLinear(200 / 255.0f) * 0.5f, 1e-5f);
  EXPECT_NEAR(corner.y, 0.0f, 1e-6f);
}

// The same quad as a GLB with the PNG inside its binary chunk.
void writeTexturedGlb(const fs::path& dir, const fs::path& png) {
  const float positions[12] = {0, 0, 0, 1, 0, 0, 1, 0, -1, 0, 0, -1};
  const float uvs[8] = {0, 0, 1, 0, 1, 1, 0, 1};
  const uint16_t indices[6] = {0, 1, 2, 0, 2, 3};
  std::string bin(reinterpret_cast<const char*>(positions), sizeof positions);
  bin.append(reinterpret_cast<const char*>(uvs), sizeof uvs);
  bin.append(reinterpret_cast<const char*>(indices), sizeof indices);
  std::ifstream in(png, std::ios::binary);
  const std::string image((std::istreambuf_iterator<char>(in)), {});
  bin += image;
  while (bin.size() % 4) bin.push_back('\0');
  std::string json = R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
  "materials": [{"name": "painted", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
  "textures": [{"source": 0}], "images": [{"bufferView": 3, "mimeType": "image/png"}],
  "buffers": [{"byteLength": )" + std::to_string(bin.size()) + R"(}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 32},
                  {"buffer": 0, "byteOffset": 80, "byteLength": 12},
                  {"buffer": 0, "byteOffset": 92, "byteLength": )" + std::to_string(image.size()) + R"(}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, -1], "max": [1, 0, 0]},
                {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
                {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}]})";
  while (json.size() % 4) json.push_back(' ');
  const auto word = [](std::string& out, uint32_t value) { out.append(reinterpret_cast<const char*>(&value), 4); };
  std::string glb;
  word(glb, 0x46546C67);   // "glTF"
  word(glb, 2);
  word(glb, uint32_t(12 + 8 + json.size() + 8 + bin.size()));
  word(glb, uint32_t(json.size()));
  word(glb, 0x4E4F534A);   // "JSON"
  glb += json;
  word(glb, uint32_t(bin.size()));
  word(glb, 0x004E4942);   // "BIN"
  glb += bin;
  writeText(dir / "quad.glb", glb);
}

TEST(Textures, AnImageEmbeddedInAGlbIsCopiedIntoTheStore) {
  TempDirectory dir;
  writePng(dir / "embedded.png", 2, 2, kTexels);
  writeTexturedGlb(dir.path(), dir / "embedded.png");
  fs::remove(dir / "embedded.png");
  importBuilding({dir / "quad.glb"}, dir / "store");
  const SceneStore store = SceneStore::open(dir / "store");
  ASSERT_EQ(store.materials().size(), 1u);
  const Material& painted = store.materials()[0];
  ASSERT_TRUE(painted.textured());
  const Vec3 bottomRight = AlbedoTextures::instance().albedoAt(store.directory(), painted, Uv{0.75f, 0.25f});
  EXPECT_NEAR(bottomRight.x, painted.albedo.x, 1e-5f);   // the white texel
  const Vec3 topLeft = AlbedoTextures::instance().albedoAt(store.directory(), painted, Uv{0.25f, 0.75f});
  EXPECT_NEAR(topLeft.x, srgbToLinear(200 / 255.0f) * painted.albedo.x, 1e-5f);
  EXPECT_NEAR(topLeft.y, 0.0f, 1e-6f);
}

TEST(Textures, AMissingTextureIsAnErrorNamingTheMaterialAndThePath) {
  TempDirectory dir;
  writeTexturedObj(dir.path(), "missing/wood.png");
  const std::string error = errorOf([&] { importBuilding({dir / "quad.obj"}, dir / "store"); });
  EXPECT_NE(error.find("material 'painted'"), std::string::npos) << error;
  EXPECT_NE(error.find("missing/wood.png"), std::string::npos) << error;
  EXPECT_NE(error.find("does not exist"), std::string::npos) << error;
  EXPECT_EQ(error.find('\n'), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(dir / "store"));
}

TEST(Textures, ATextureThatIsNotAnImageIsAnErrorNamingTheMaterial) {
  TempDirectory dir;
  writeText(dir / "tex.png", "not a png");
  writeTexturedObj(dir.path());
  const std::string error = errorOf([&] { importBuilding({dir / "quad.obj"}, dir / "store"); });
  EXPECT_NE(error.find("material 'painted'"), std::string::npos) << error;
  EXPECT_NE(error.find("tex.png"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(dir / "store"));
}

}  // namespace
}  // namespace portico
