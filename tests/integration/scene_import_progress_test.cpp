// `portico scene import` of a building of many objects (one mesh file
// each, a few milliseconds apiece) says how far it has got.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;

TEST(SceneImport, ABuildingOfManyObjectsShowsProgress) {
  const fs::path dir = makeTempDirectory("import-progress");
  constexpr int kObjects = 1000;
  fs::create_directories(dir / "meshes");
  std::ofstream json(dir / "building.json");
  json << "{\"camera\": {\"origin\": [5, 3, -5], \"target\": [5, 0, 5]}, \"objects\": [\n";
  for (int i = 0; i < kObjects; ++i) {
    const double x = (i % 40) * 0.25, z = (i / 40) * 0.25;
    std::ofstream(dir / "meshes" / (std::to_string(i) + ".obj"))
        << "v " << x << " 0 " << z << "\nv " << x + 0.1 << " 0 " << z << "\nv " << x << " 0.1 " << z << "\nf 1 2 3\n";
    json << "{\"obj\": \"meshes/" << i << ".obj\", \"albedo\": [0.5, 0.5, 0.5]},\n";
  }
  std::ofstream(dir / "light.obj") << "v 0 4 0\nv 10 4 0\nv 10 4 10\nv 0 4 10\nf 1 3 2\nf 1 4 3\n";
  json << "{\"obj\": \"light.obj\", \"albedo\": [0, 0, 0], \"emission\": [1, 1, 1]}]}\n";
  json.close();
  const fs::path log = dir / "import.log";
  ASSERT_EQ(runCommand({kBin + "portico", "scene", "import", (dir / "building.json").string(), (dir / "store").string()},
                       log),
            0)
      << readFile(log);
  const std::string text = readFile(log);
  const std::string total = std::to_string(kObjects + 1);
  EXPECT_NE(text.find("reading mesh files: 1 of " + total + " objects"), std::string::npos) << text;
  EXPECT_NE(text.find("reading mesh files: " + total + " of " + total + " objects (100 %"), std::string::npos) << text;
}

}  // namespace
}  // namespace portico
