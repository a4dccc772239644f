// Every number a job takes is bounded, through real processes: the client
// refuses a value out of range in one line before connecting, the
// coordinator refuses a hand-made message beyond the bounds and goes on
// answering, an import refuses duplicate portals, and a light bright
// enough to overflow the film fails its job saying so instead of giving
// wrapped, negative pixels.
#include <capnp/message.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>

#include "common/net/client.h"
#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;

class Bounds : public DemoStoreSuite<Bounds> {
 protected:
  // The two_rooms reference scene, its JSON changed by `edit`, imported into
  // dir/store; returns the import's exit status (its log in dir/import.log).
  static int importEditedTwoRooms(const fs::path& dir, const std::function<void(nlohmann::json&)>& edit) {
    const fs::path source = fs::path(PORTICO_SOURCE_DIR) / "tests/scenes/two_rooms";
    fs::create_directories(dir / "scene");
    for (const auto& entry : fs::directory_iterator(source))
      if (entry.path().extension() == ".obj") fs::copy_file(entry.path(), dir / "scene" / entry.path().filename());
    nlohmann::json scene = nlohmann::json::parse(readFile(source / "scene.json"));
    edit(scene);
    std::ofstream(dir / "scene" / "scene.json") << scene.dump();
    return runCommand({kBin + "portico", "scene", "import", (dir / "scene" / "scene.json").string(),
                       (dir / "store").string()},
                      dir / "import.log");
  }
};

// The client checks before it connects (the endpoint here has no one
// behind it): a negative count does not wrap to 2^64-1, a size of 1e30 is
// not "0 MiB", and each error names the option and its bounds.
TEST_F(Bounds, TheClientRefusesNumbersOutOfRangeBeforeConnecting) {
  const std::vector<std::string> submit{kBin + "portico", "submit", "--coordinator", "tcp://127.0.0.1:1",
                                        "--timeout", "0.2", store_.string(), "-o", (dir_ / "x.png").string()};
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases{
      {{"--photons", "-1"}, "--photons"},          {{"--photons", "100000000000"}, "--photons"},
      {{"--gather", "4000000000"}, "--gather"},    {{"--light-samples", "4000000000"}, "--light-samples"},
      {{"--spp", "0"}, "--spp"},                   {{"--photon-k", "1000000"}, "--photon-k"},
      {{"--seed", "-1"}, "--seed"},                {{"--exposure", "nan"}, "--exposure"},
      {{"--photon-radius", "1e30"}, "--photon-radius"}, {{"--width", "-5"}, "--width"}};
  int index = 0;
  for (const auto& [options, name] : cases) {
    std::vector<std::string> argv = submit;
    argv.insert(argv.end(), options.begin(), options.end());
    const fs::path log = dir_ / ("client-" + std::to_string(index++) + ".log");
    const auto started = std::chrono::steady_clock::now();
    EXPECT_NE(runCommand(argv, log), 0) << options[0] << " " << options[1];
    const std::string output = readFile(log);
    EXPECT_NE(output.find(name), std::string::npos) << output;
    EXPECT_NE(output.find("number from"), std::string::npos) << options[0] << " " << options[1] << ": " << output;
    EXPECT_LT(std::chrono::steady_clock::now() - started, std::chrono::seconds(5));
  }
  // --memory, for `portico render` and for a worker.
  const fs::path renderLog = dir_ / "render-memory.log";
  EXPECT_NE(runCommand({kBin + "portico", "render", store_.string(), "-o", (dir_ / "y.png").string(), "--memory",
                        "1e30"},
                       renderLog),
            0);
  EXPECT_NE(readFile(renderLog).find("too large"), std::string::npos) << readFile(renderLog);
  const fs::path workerLog = dir_ / "worker-memory.log";
  EXPECT_NE(runCommand({kBin + "portico-worker", "--connect", "tcp://127.0.0.1:1", "--memory", "1e30"}, workerLog), 0);
  EXPECT_NE(readFile(workerLog).find("too large"), std::string::npos) << readFile(workerLog);
}

// A hand-made Submit beyond the bounds is refused by the coordinator, which
// still answers at once (2^64-1 photons would keep it queueing forever).
TEST_F(Bounds, TheCoordinatorRefusesAHandMadeSpecBeyondTheBoundsAndGoesOnAnswering) {
  const fs::path dir = dir_ / "coordinator";
  LocalCluster cluster(dir, 0);
  struct Case {
    std::string field;
    std::function<void(wire::JobSpec::Builder)> set;
  };
  const std::vector<Case> cases{
      {"photons", [](auto spec) { spec.setPhotons(UINT64_MAX); }},
      {"gather", [](auto spec) { spec.setGather(4000000000u); }},
      {"light samples", [](auto spec) { spec.setLightSamples(4000000000u); }},
      {"photon k", [](auto spec) { spec.setPhotonK(4000000000u); }},
      {"photon radius", [](auto spec) { spec.setPhotonRadius(std::numeric_limits<float>::infinity()); }},
      {"exposure", [](auto spec) { spec.setExposure(std::numeric_limits<float>::quiet_NaN()); }},
      {"image width", [](auto spec) { spec.setWidth(4000000000u); }},
      {"light hops", [](auto spec) { spec.setLightHops(-7); }},
      {"camera samples", [](auto spec) {
         spec.setWidth(16384);
         spec.setHeight(16384);
         spec.setSpp(65536);
       }}};
  for (const Case& c : cases) {
    net::CoordinatorClient client(cluster.endpoint(), "", std::chrono::seconds(5));
    capnp::MallocMessageBuilder message;
    auto spec = message.initRoot<wire::Envelope>().initSubmit().initSpec();
    spec.setStore(store_.string());
    spec.setOutput((dir / "image.png").string());
    spec.setPhotons(1000);
    spec.setSpp(1);
    spec.setWidth(32);
    spec.setHeight(32);
    spec.setPhotonRadius(0.5f);
    spec.setExposure(1);
    c.set(spec);
    std::string error;
    try {
      client.submit(message);
    } catch (const std::exception& e) {
      error = e.what();
    }
    EXPECT_NE(error.find(c.field), std::string::npos) << c.field << ": '" << error << "'";
    EXPECT_EQ(error.find("no answer"), std::string::npos) << c.field << ": " << error;
  }
  const auto all = cluster.status(0);
  EXPECT_TRUE(all["jobs"].empty()) << all.dump();
}

// The same portal given twice (here five thousand times) would make every
// ray of its cells test them all: the import refuses the file, naming both.
TEST_F(Bounds, DuplicatePortalsAreRefusedAtImport) {
  const fs::path dir = dir_ / "duplicates";
  const int code = importEditedTwoRooms(dir, [](nlohmann::json& scene) {
    const nlohmann::json portal = scene["portals"][0];
    for (int i = 0; i < 5000; ++i) scene["portals"].push_back(portal);
  });
  const std::string log = readFile(dir / "import.log");
  EXPECT_NE(code, 0) << log;
  EXPECT_NE(log.find("duplicates portals[0]"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(dir / "store" / "scene.db"));
}

// Emission of 1e14 W/m^2/sr: its pixels are beyond the fixed-point film's
// range (2.7e11). The job fails with a message saying so, rather than
// finish with wrapped, negative pixels.
TEST_F(Bounds, ALightBrightEnoughToOverflowTheFilmFailsTheJobSayingSo) {
  const fs::path dir = dir_ / "bright";
  ASSERT_EQ(importEditedTwoRooms(dir,
                                 [](nlohmann::json& scene) {
                                   for (auto& object : scene["objects"])
                                     if (object.contains("emission") && !object["emission"].is_null())
                                       object["emission"] = {1e14, 1e14, 1e14};
                                 }),
            0)
      << readFile(dir / "import.log");
  LocalCluster cluster(dir, 1);
  const auto status = cluster.render(dir / "store", dir / "image.exr", 2000, 1);
  EXPECT_EQ(status.value("state", ""), "failed") << status.dump(2);
  EXPECT_NE(status.value("error", "").find("film's range"), std::string::npos) << status.dump(2);
  EXPECT_FALSE(fs::exists(dir / "image.exr"));
}

}  // namespace
}  // namespace portico
