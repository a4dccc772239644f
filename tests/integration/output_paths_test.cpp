// Image outputs: checked when a job is submitted (by the client as the user
// who asks, and by the coordinator as itself), never a directory created on
// anyone's behalf, and a finished job whose image could not be written
// keeps it: `portico fetch-image` writes it, with the same bits.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <tuple>

#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;

class Outputs : public DemoStoreSuite<Outputs> {};
TEST_F(Outputs, BadPathsAreRefusedAtSubmitNamingTheProblemAndNothingIsCreated) {
  const fs::path dir = dir_ / "bad";
  LocalCluster cluster(dir, 0);
  const std::vector<std::pair<fs::path, std::string>> cases{
      {dir / "missing" / "y.png", "directory " + (dir / "missing").string() + " does not exist"},
      {dir / "no-extension", "has no image extension"},
      {dir / "image.bmpx", "unknown image extension .bmpx"},
      {dir, "is a directory"},
      // Longer than a file name may be with OUTPUT.json.tmp beside it (it used to fail only at writing).
      {dir / (std::string(300, 'a') + ".png"), "its name is 304 bytes"}};
  int index = 0;
  for (const auto& [output, expected] : cases) {
    const std::string name = "submit-" + std::to_string(index++);
    int code = -1;
    captureOutput({kBin + "portico", "submit", "--coordinator", cluster.endpoint(), store_.string(), "-o", output.string()},
                  dir, name, &code);
    EXPECT_NE(code, 0) << output;
    const std::string log = readFile(dir / (name + ".log"));
    EXPECT_NE(log.find("output " + output.string()), std::string::npos) << log;
    EXPECT_NE(log.find(expected), std::string::npos) << log;
  }
  // The coordinator checks too (a client that skips the check).
  try {
    cluster.submit(store_, dir / "missing" / "y.exr", 2000, 1);
    ADD_FAILURE() << "the coordinator accepted an output in a missing directory";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("directory " + (dir / "missing").string() + " does not exist"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(fs::exists(dir / "missing"));
  try {
    cluster.submit(store_, dir / (std::string(300, 'a') + ".exr"), 2000, 1);
    ADD_FAILURE() << "the coordinator accepted an output name of 304 bytes";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("its name is 304 bytes"), std::string::npos) << e.what();
  }
  // Relative paths would be read against the coordinator's working
  // directory: a Submit names absolute ones (the client resolves them).
  for (const auto& [store, output, what] :
       {std::tuple<fs::path, fs::path, std::string>{"demo", dir / "y.exr", "scene store 'demo' is a relative path"},
        {store_, "y.exr", "output 'y.exr' is a relative path"}}) {
    try {
      cluster.submit(store, output, 2000, 1);
      ADD_FAILURE() << "the coordinator accepted a relative path: " << what;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(cluster.status(0)["jobs"].size(), 0u);
}

// `portico render` keeps its services' folder (jobs.db, the photon files)
// under $TMPDIR, and names a TMPDIR it cannot use.
TEST_F(Outputs, RenderRunsItsServicesUnderTmpdir) {
  const fs::path dir = dir_ / "tmpdir", temp = dir / "temp";
  fs::create_directories(temp);
  const std::vector<std::string> render{kBin + "portico", "render", store_.string(), "-o", (dir / "x.exr").string(),
                                        "--workers", "1", "--photons", "2000", "--spp", "1", "--width", "8",
                                        "--height", "8", "--keep-logs"};
  ::setenv("TMPDIR", temp.c_str(), 1);
  int code = -1;
  captureOutput(render, dir, "render", &code);
  ::setenv("TMPDIR", (dir / "missing").c_str(), 1);
  int missingCode = -1;
  captureOutput(render, dir, "render-missing", &missingCode);
  ::unsetenv("TMPDIR");

  ASSERT_EQ(code, 0) << readFile(dir / "render.log");
  const std::string log = readFile(dir / "render.log"), kept = "logs and jobs.db kept in ";
  const size_t at = log.find(kept);
  ASSERT_NE(at, std::string::npos) << log;
  const fs::path folder = log.substr(at + kept.size(), log.find('\n', at) - at - kept.size());
  EXPECT_EQ(folder.parent_path(), temp) << log;
  EXPECT_TRUE(fs::exists(folder / "jobs.db")) << folder;
  EXPECT_NE(missingCode, 0);
  EXPECT_NE(readFile(dir / "render-missing.log").find("cannot create a temporary directory under " + (dir / "missing").string()),
            std::string::npos)
      << readFile(dir / "render-missing.log");
}

TEST_F(Outputs, AnImageThatCouldNotBeWrittenIsKeptAndFetchedWithTheSameBits) {
  const fs::path dir = dir_ / "recover";
  LocalCluster cluster(dir, 0);   // no worker yet: the job waits while its directory goes
  const fs::path gone = dir / "gone";
  fs::create_directories(gone);
  const uint64_t job = cluster.submit(store_, gone / "image.exr", 5000, 1);
  fs::remove_all(gone);
  cluster.addWorker({});
  const auto status = cluster.wait(job);
  ASSERT_EQ(status.value("state", ""), "done") << status.dump(2);
  const std::string error = status.value("error", "");
  EXPECT_NE(error.find("the image could not be written"), std::string::npos) << status.dump(2);
  EXPECT_NE(error.find("portico fetch-image " + std::to_string(job) + " -o FILE"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(gone));   // not created again on the client's behalf

  int code = -1;
  captureOutput({kBin + "portico", "wait", "--coordinator", cluster.endpoint(), std::to_string(job), "--quiet"}, dir,
                "wait", &code);
  EXPECT_EQ(code, 1) << readFile(dir / "wait.log");   // done, but the image the user asked for is not there
  // ... and it says why, even with --quiet, not only "done".
  EXPECT_NE(readFile(dir / "wait.log").find("done in"), std::string::npos) << readFile(dir / "wait.log");
  EXPECT_NE(readFile(dir / "wait.log").find("but the image could not be written"), std::string::npos)
      << readFile(dir / "wait.log");
  captureOutput({kBin + "portico", "fetch-image", "--coordinator", cluster.endpoint(), std::to_string(job), "-o",
                 (dir / "fetched.exr").string()},
                dir, "fetch", &code);
  ASSERT_EQ(code, 0) << readFile(dir / "fetch.log");
  EXPECT_EQ(nlohmann::json::parse(readFile(dir / "fetched.exr.json"))["job"], job);
  // Another extension than the job's is refused: the bytes are an EXR.
  captureOutput({kBin + "portico", "fetch-image", "--coordinator", cluster.endpoint(), std::to_string(job), "-o",
                 (dir / "fetched.png").string()},
                dir, "fetch-png", &code);
  EXPECT_NE(code, 0);
  EXPECT_NE(readFile(dir / "fetch-png.log").find("is a .exr file"), std::string::npos) << readFile(dir / "fetch-png.log");

  // The same job written by the coordinator: the same bits.
  const auto direct = cluster.render(store_, dir / "direct.exr", 5000, 1);
  ASSERT_EQ(direct.value("state", ""), "done") << direct.dump(2);
  EXPECT_EQ(direct.value("error", ""), "");
  EXPECT_EQ(differingFloats(dir / "fetched.exr", dir / "direct.exr"), 0u);
}

}  // namespace
}  // namespace portico
