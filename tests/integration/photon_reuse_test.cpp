// Photon-pass reuse: a job on the same store with the same photon settings
// renders with an earlier job's finished photon pass, and `portico render
// --views` renders several views after one photon pass. Real coordinator and
// workers; two_rooms at small sizes.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;

// Two views, one per room of two_rooms.
const std::vector<std::string> kRoomB{"--look-from", "3.5,1.5,1", "--look-at", "0,1,0"};
const std::vector<std::string> kRoomA{"--look-from", "-3.5,1.5,-1", "--look-at", "-0.5,1,0", "--fov", "70"};
// The settings every job here shares (those of LocalCluster::submit's too).
const std::vector<std::string> kSmall{"--photons", "20000", "--spp", "1", "--gather", "2", "--width", "48",
                                      "--height", "32", "--seed", "7", "--light-samples", "1", "--photon-k", "32"};

class PhotonReuse : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = makeTempDirectory("photon-reuse");
    store_ = dir_ / "two_rooms";
    const int code = runCommand({kBin + "portico", "scene", "import",
                                 std::string(PORTICO_SOURCE_DIR) + "/tests/scenes/two_rooms/scene.json", store_.string()},
                                dir_ / "import.log");
    ASSERT_EQ(code, 0) << readFile(dir_ / "import.log");
  }

  // argv followed by `extra`; an option given twice (CLI11 takes each once)
  // keeps its last value.
  static std::vector<std::string> with(std::vector<std::string> argv, const std::vector<std::string>& extra) {
    for (size_t i = 0; i < extra.size(); ++i) {
      const bool valued = extra[i].rfind("--", 0) == 0 && i + 1 < extra.size() && extra[i + 1].rfind("--", 0) != 0;
      auto given = std::find(argv.begin(), argv.end(), extra[i]);
      if (valued && given != argv.end() && given + 1 != argv.end()) {
        *(given + 1) = extra[++i];
        continue;
      }
      argv.push_back(extra[i]);
      if (valued) argv.push_back(extra[++i]);
    }
    return argv;
  }

  // `portico render` of one view alone.
  static int renderAlone(const std::string& name, int workers, const std::vector<std::string>& view) {
    auto argv = with({kBin + "portico", "render", store_.string(), "-o", (dir_ / (name + ".exr")).string(),
                      "--workers", std::to_string(workers)},
                     kSmall);
    return runCommand(with(argv, view), dir_ / (name + ".log"));
  }

  static int renderViews(const std::string& name, int workers, const std::string& viewsFile,
                         const std::vector<std::string>& extra = {}) {
    auto argv = with({kBin + "portico", "render", store_.string(), "--views", viewsFile, "-o",
                      (dir_ / name).string(), "--workers", std::to_string(workers)},
                     kSmall);
    return runCommand(with(argv, extra), dir_ / (name + ".log"));
  }

  static fs::path writeFile(const std::string& name, const std::string& text) {
    const fs::path path = dir_ / name;
    std::ofstream(path) << text;
    return path;
  }

  static nlohmann::json statistics(const fs::path& image) {
    return nlohmann::json::parse(readFile(image.string() + ".json"));
  }

  // `portico submit` to a running coordinator; returns the job id.
  static uint64_t submit(LocalCluster& cluster, const std::string& name, const std::vector<std::string>& extra) {
    int code = 0;
    auto argv = with({kBin + "portico", "submit", "--coordinator", cluster.endpoint(), store_.string(), "-o",
                      (dir_ / (name + ".exr")).string()},
                     kSmall);
    const std::string out = captureOutput(with(argv, extra), dir_, name, &code);
    EXPECT_EQ(code, 0) << readFile(dir_ / (name + ".log"));
    return code == 0 ? std::stoull(out) : 0;
  }

  static nlohmann::json reusedFrom(const nlohmann::json& status) { return status["photon_pass"]["reused_from_job"]; }

  static inline fs::path dir_, store_;
};

const char* kTwoViews = R"([
  {"name": "roomB", "look_from": [3.5, 1.5, 1], "look_at": [0, 1, 0]},
  {"name": "roomA", "look_from": [-3.5, 1.5, -1], "look_at": [-0.5, 1, 0], "fov": 70}
])";

TEST_F(PhotonReuse, ViewsRunOnePhotonPassAndEachImageHasTheBitsOfItsViewRenderedAlone) {
  const fs::path views = writeFile("two-views.json", kTwoViews);
  ASSERT_EQ(renderViews("views-2", 2, views.string()), 0) << readFile(dir_ / "views-2.log");
  ASSERT_EQ(renderViews("views-1", 1, views.string()), 0) << readFile(dir_ / "views-1.log");
  for (const std::string run : {"views-1", "views-2"}) {
    const auto first = statistics(dir_ / run / "roomB.exr"), second = statistics(dir_ / run / "roomA.exr");
    // The first view's job ran the photon pass; the second emitted nothing
    // and rendered with the first's photon tables.
    EXPECT_TRUE(reusedFrom(first).is_null()) << run;
    EXPECT_EQ(first["photon_pass"]["photons_emitted_by_this_job"].get<int64_t>(), 20000) << run;
    EXPECT_EQ(reusedFrom(second), first["job"]) << run;
    EXPECT_EQ(second["photon_pass"]["photons_emitted_by_this_job"].get<int64_t>(), 0) << run;
    EXPECT_EQ(second["photons"], first["photons"]) << run;
    expectConservation(second);
    EXPECT_GT(second["rays"]["camera"].get<int64_t>(), 0) << run;
  }
  ASSERT_EQ(renderAlone("alone-roomB", 2, kRoomB), 0) << readFile(dir_ / "alone-roomB.log");
  ASSERT_EQ(renderAlone("alone-roomA", 1, kRoomA), 0) << readFile(dir_ / "alone-roomA.log");
  for (const std::string run : {"views-1", "views-2"}) {
    EXPECT_EQ(differingFloats(dir_ / run / "roomB.exr", dir_ / "alone-roomB.exr"), 0u) << run;
    EXPECT_EQ(differingFloats(dir_ / run / "roomA.exr", dir_ / "alone-roomA.exr"), 0u) << run;
  }
  EXPECT_GT(differingFloats(dir_ / "views-2" / "roomA.exr", dir_ / "views-2" / "roomB.exr"), 0u);
}

TEST_F(PhotonReuse, ViewsTakeTheirOwnSizeAndSppAndTheFormatAsked) {
  const fs::path views = writeFile("sized-views.json", R"([
    {"name": "wide", "look_from": [3.5, 1.5, 1], "look_at": [0, 1, 0], "width": 40, "height": 20, "spp": 2},
    {"name": "plain", "look_from": [-3.5, 1.5, -1], "look_at": [-0.5, 1, 0]}
  ])");
  ASSERT_EQ(renderViews("sized", 2, views.string(), {"--format", "png"}), 0) << readFile(dir_ / "sized.log");
  const auto wide = statistics(dir_ / "sized" / "wide.png"), plain = statistics(dir_ / "sized" / "plain.png");
  EXPECT_EQ(wide["settings"]["width"], 40);
  EXPECT_EQ(wide["settings"]["height"], 20);
  EXPECT_EQ(wide["settings"]["spp"], 2);
  EXPECT_EQ(plain["settings"]["width"], 48);
  EXPECT_EQ(plain["settings"]["spp"], 1);
  EXPECT_EQ(reusedFrom(plain), wide["job"]);
}

TEST_F(PhotonReuse, SubmitReusesTheSamePhotonSettingsButNotOtherPhotonsNorFreshPhotons) {
  LocalCluster cluster(dir_ / "submit-cluster", 2);
  const uint64_t first = submit(cluster, "s-first", kRoomA);
  const nlohmann::json firstStatus = cluster.wait(first);
  ASSERT_EQ(firstStatus.value("state", ""), "done");
  const uint64_t reusing = submit(cluster, "s-reusing", kRoomB);
  const uint64_t fresh = submit(cluster, "s-fresh", with(kRoomB, {"--fresh-photons"}));
  const uint64_t otherPhotons = submit(cluster, "s-other-photons", with(kRoomB, {"--photons", "30000"}));
  const uint64_t otherRadius = submit(cluster, "s-other-radius", with(kRoomB, {"--photon-radius", "0.4"}));
  // Gathering is the render phase's: reused, with photon maps built another way.
  const uint64_t noGather = submit(cluster, "s-no-gather", with(kRoomB, {"--gather", "0"}));
  const nlohmann::json status = cluster.wait(reusing);
  ASSERT_EQ(status.value("state", ""), "done") << status.dump();
  EXPECT_EQ(reusedFrom(status), first);
  EXPECT_EQ(status["photon_pass"]["photons_emitted_by_this_job"].get<int64_t>(), 0);
  // Its photon phase only passes through (a millisecond or so between submit
  // and the render phase), far shorter than the pass it reuses.
  EXPECT_LT(status["time_ms"]["photons"].get<int64_t>(), firstStatus["time_ms"]["photons"].get<int64_t>());
  for (uint64_t job : {fresh, otherPhotons, otherRadius}) {
    const nlohmann::json own = cluster.wait(job);
    ASSERT_EQ(own.value("state", ""), "done") << own.dump();
    EXPECT_TRUE(reusedFrom(own).is_null()) << job;
    EXPECT_GT(own["photon_pass"]["photons_emitted_by_this_job"].get<int64_t>(), 0) << job;
  }
  const nlohmann::json noGatherStatus = cluster.wait(noGather);
  ASSERT_EQ(noGatherStatus.value("state", ""), "done") << noGatherStatus.dump();
  // The newest finished pass with the same photon settings: the first's, or the fresh one's.
  EXPECT_TRUE(reusedFrom(noGatherStatus) == first || reusedFrom(noGatherStatus) == fresh) << noGatherStatus.dump();
  // The same view with its own pass and with a reused one: the same bits.
  EXPECT_EQ(differingFloats(dir_ / "s-reusing.exr", dir_ / "s-fresh.exr"), 0u);
  EXPECT_GT(differingFloats(dir_ / "s-reusing.exr", dir_ / "s-other-photons.exr"), 0u);
  const uint64_t noGatherFresh = submit(cluster, "s-no-gather-fresh", with(kRoomB, {"--gather", "0", "--fresh-photons"}));
  ASSERT_EQ(cluster.wait(noGatherFresh).value("state", ""), "done");
  EXPECT_EQ(differingFloats(dir_ / "s-no-gather.exr", dir_ / "s-no-gather-fresh.exr"), 0u);
}

TEST_F(PhotonReuse, AReusingJobSurvivesACoordinatorRestartWithTheSameBits) {
  LocalCluster cluster(dir_ / "restart-cluster", 1);
  const uint64_t first = submit(cluster, "r-first", kRoomA);
  ASSERT_EQ(cluster.wait(first).value("state", ""), "done");
  const std::vector<std::string> longer{"--spp", "24", "--width", "96", "--height", "64"};
  const uint64_t reusing = submit(cluster, "r-reusing", with(kRoomB, longer));
  ASSERT_TRUE(waitUntil([&] { return cluster.status(reusing)["progress"].value("camera_rays_done", 0) > 0; },
                        std::chrono::seconds(60)));
  const std::string endpoint = cluster.endpoint();   // the workers reconnect to it
  cluster.killCoordinator();
  cluster.startCoordinator(endpoint);
  const nlohmann::json status = cluster.wait(reusing);
  ASSERT_EQ(status.value("state", ""), "done") << status.dump();
  EXPECT_EQ(reusedFrom(status), first);
  EXPECT_EQ(status["photon_pass"]["photons_emitted_by_this_job"].get<int64_t>(), 0);
  const uint64_t fresh = submit(cluster, "r-fresh", with(with(kRoomB, longer), {"--fresh-photons"}));
  ASSERT_EQ(cluster.wait(fresh).value("state", ""), "done");
  EXPECT_EQ(differingFloats(dir_ / "r-reusing.exr", dir_ / "r-fresh.exr"), 0u);
}

// A lender's photon file that lost bytes (an operating-system crash) is
// not offered; one whose bytes changed under the same size fails its CRC
// when a worker fetches it: the reusing job runs a photon pass of its own
// (same bits), and the damaged pass is never offered again.
TEST_F(PhotonReuse, ADamagedLenderIsNotReusedAndAReusingJobThatFindsItDamagedRunsItsOwnPass) {
  const fs::path clusterDir = dir_ / "damage-cluster";
  LocalCluster cluster(clusterDir, 1);
  const uint64_t first = submit(cluster, "d-first", kRoomA);
  ASSERT_EQ(cluster.wait(first).value("state", ""), "done");
  const fs::path photons = clusterDir / "jobs.db-photons" / fmt::format("job-{}.bin", first);
  ASSERT_TRUE(fs::exists(photons));
  {
    // Two bytes of every 4 KiB block: batches lie after deposit regions'
    // heads (coordinator/deposit_regions.h), wherever the leases put them.
    std::fstream file(photons, std::ios::in | std::ios::out | std::ios::binary);
    for (uintmax_t at = 100; at + 2 <= fs::file_size(photons); at += 4096) {
      file.seekp(std::streamoff(at));
      file.put('\x5a');
      file.put('\xa5');
    }
  }
  // A new worker, which has cached no photon map of job 1's: it fetches the tables.
  cluster.worker(0).stop();
  cluster.addWorker({});
  const uint64_t reusing = submit(cluster, "d-reusing", kRoomB);
  const nlohmann::json status = cluster.wait(reusing);
  ASSERT_EQ(status.value("state", ""), "done") << status.dump();
  EXPECT_TRUE(reusedFrom(status).is_null()) << status.dump();
  EXPECT_EQ(status["photon_pass_restarts"].get<int64_t>(), 1);
  EXPECT_EQ(status["photon_pass"]["photons_emitted_by_this_job"].get<int64_t>(), 20000);
  // Job 1 lends no more; the reusing job's own pass is the one offered now.
  const uint64_t next = submit(cluster, "d-next", kRoomB);
  const nlohmann::json nextStatus = cluster.wait(next);
  EXPECT_EQ(reusedFrom(nextStatus), reusing) << nextStatus.dump();
  EXPECT_EQ(differingFloats(dir_ / "d-reusing.exr", dir_ / "d-next.exr"), 0u);
  // A photon file cut short is not offered at all.
  fs::resize_file(clusterDir / "jobs.db-photons" / fmt::format("job-{}.bin", reusing), 64);
  const uint64_t afterCut = submit(cluster, "d-after-cut", kRoomB);
  const nlohmann::json cutStatus = cluster.wait(afterCut);
  EXPECT_TRUE(reusedFrom(cutStatus).is_null()) << cutStatus.dump();
  EXPECT_EQ(cutStatus["photon_pass_restarts"].get<int64_t>(), 0);
  EXPECT_EQ(differingFloats(dir_ / "d-reusing.exr", dir_ / "d-after-cut.exr"), 0u);
}

// A store regenerated in place (new files renamed over the old, even with
// the same content) is another store: its jobs run their own photon pass.
TEST_F(PhotonReuse, AStoreRegeneratedInPlaceIsNotMistakenForTheOldOne) {
  const fs::path store = dir_ / "regenerated";
  const std::vector<std::string> import{kBin + "portico", "scene", "import",
                                        std::string(PORTICO_SOURCE_DIR) + "/tests/scenes/two_rooms/scene.json",
                                        store.string()};
  ASSERT_EQ(runCommand(import, dir_ / "regenerate-1.log"), 0) << readFile(dir_ / "regenerate-1.log");
  LocalCluster cluster(dir_ / "regenerate-cluster", 1);
  const auto submitTo = [&](const std::string& name) {
    int code = 0;
    auto argv = with({kBin + "portico", "submit", "--coordinator", cluster.endpoint(), store.string(), "-o",
                      (dir_ / (name + ".exr")).string()},
                     with(kSmall, kRoomB));
    const std::string out = captureOutput(argv, dir_, name, &code);
    EXPECT_EQ(code, 0) << readFile(dir_ / (name + ".log"));
    return code == 0 ? std::stoull(out) : 0;
  };
  const uint64_t first = submitTo("g-first");
  ASSERT_EQ(cluster.wait(first).value("state", ""), "done");
  EXPECT_EQ(reusedFrom(cluster.wait(submitTo("g-same"))), first);
  ASSERT_EQ(runCommand(import, dir_ / "regenerate-2.log"), 0) << readFile(dir_ / "regenerate-2.log");
  const nlohmann::json after = cluster.wait(submitTo("g-after"));
  EXPECT_EQ(after.value("state", ""), "done") << after.dump();
  EXPECT_TRUE(reusedFrom(after).is_null()) << after.dump();
}

// A view may name a store camera: it renders as `--camera NAME` alone does.
TEST_F(PhotonReuse, AViewNamingAStoreCameraHasTheBitsOfThatCameraRenderedAlone) {
  const fs::path views =
      writeFile("named.json", R"([{"name": "first", "look_from": [3.5, 1.5, 1], "look_at": [0, 1, 0]},
                                  {"name": "stored", "camera": "default"}])");
  ASSERT_EQ(renderViews("views-named", 2, views.string()), 0) << readFile(dir_ / "views-named.log");
  EXPECT_EQ(reusedFrom(statistics(dir_ / "views-named" / "stored.exr")),
            statistics(dir_ / "views-named" / "first.exr")["job"]);
  ASSERT_EQ(renderAlone("alone-default", 2, {"--camera", "default"}), 0) << readFile(dir_ / "alone-default.log");
  EXPECT_EQ(differingFloats(dir_ / "views-named" / "stored.exr", dir_ / "alone-default.exr"), 0u);
}

// A camera for every view from the command line is refused: each view has its own.
TEST_F(PhotonReuse, ViewsRefuseACameraGivenForThemAll) {
  const fs::path views = writeFile("one-view.json", R"([{"name": "a", "camera": "default"}])");
  for (const std::vector<std::string>& extra :
       {std::vector<std::string>{"--camera", "default"}, {"--look-from", "3,1,1", "--look-at", "0,1,0"}}) {
    const std::string run = "views-with-" + extra[0].substr(2);
    EXPECT_NE(renderViews(run, 1, views.string(), extra), 0) << run;
    const std::string log = readFile(dir_ / (run + ".log"));
    EXPECT_NE(log.find("--views gives each view its camera"), std::string::npos) << log;
  }
}

// Each refusal is one line naming the view and the problem, before any
// service starts (nothing is written in the output directory).
TEST_F(PhotonReuse, BadViewsFilesAreRefusedInOneLineNamingTheViewAndTheProblem) {
  struct Case {
    const char* name;
    const char* text;
    std::vector<std::string> expected;   // in the first line
  };
  const std::vector<Case> cases{
      {"unknown-key", R"([{"name": "a", "look_from": [3,1,1], "look_at": [0,1,0], "fov_deg": 50}])",
       {"view 1 (\"a\")", "unknown key \"fov_deg\""}},
      {"missing-at", R"([{"name": "a", "look_from": [3,1,1], "look_at": [0,1,0]}, {"name": "b", "look_from": [3,1,1]}])",
       {"view 2 (\"b\")", "\"look_at\" is missing"}},
      {"duplicate", R"([{"name": "a", "look_from": [3,1,1], "look_at": [0,1,0]}, {"name": "a", "look_from": [3,1,0], "look_at": [0,1,0]}])",
       {"view 2 (\"a\")", "names must differ"}},
      {"nan", R"([{"name": "a", "look_from": [3,NaN,1], "look_at": [0,1,0]}])", {"view 1 (\"a\")", "look_from[1]", "NaN"}},
      {"unsafe-name", R"([{"name": "../a", "look_from": [3,1,1], "look_at": [0,1,0]}])", {"view 1", "safe file name"}},
      {"no-name", R"([{"look_from": [3,1,1], "look_at": [0,1,0]}])", {"view 1", "\"name\" is missing"}},
      {"unknown-camera", R"([{"name": "a", "camera": "hall"}])", {"view 1 (\"a\")", "no camera of that name"}},
      {"camera-and-eye", R"([{"name": "a", "camera": "default", "look_from": [3,1,1]}])",
       {"view 1 (\"a\")", "takes no look_from"}},
      {"outside", R"([{"name": "a", "look_from": [30,1,1], "look_at": [0,1,0]}])", {"view 1 (\"a\")", "outside every cell"}},
      {"width-alone", R"([{"name": "a", "look_from": [3,1,1], "look_at": [0,1,0], "width": 10}])",
       {"view 1 (\"a\")", "\"width\" and \"height\""}},
      {"bad-spp", R"([{"name": "a", "look_from": [3,1,1], "look_at": [0,1,0], "spp": 0}])", {"view 1 (\"a\")", "\"spp\""}},
      {"not-a-list", R"({"name": "a"})", {"must be a JSON array"}},
  };
  for (const Case& c : cases) {
    const fs::path views = writeFile(std::string(c.name) + ".json", c.text);
    const std::string run = std::string("bad-") + c.name;
    EXPECT_NE(renderViews(run, 1, views.string()), 0) << c.name;
    const std::string log = readFile(dir_ / (run + ".log"));
    const std::string first = log.substr(0, log.find('\n'));
    EXPECT_NE(first.find(views.string()), std::string::npos) << c.name << ": " << log;
    for (const std::string& expected : c.expected) EXPECT_NE(first.find(expected), std::string::npos) << c.name << ": " << log;
    const std::string rest = log.substr(std::min(log.size(), first.size() + 1));
    EXPECT_TRUE(rest.empty() || rest == "Run with --help for more information.\n") << c.name << ": " << log;
    EXPECT_TRUE(!fs::exists(dir_ / run) || fs::is_empty(dir_ / run)) << c.name;
  }
}

}  // namespace
}  // namespace portico
