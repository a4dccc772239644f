// End to end through real processes: a coordinator and real workers over
// loopback TCP, a generated building, a finished job, an image on disk.
#include <capnp/message.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <csignal>
#include <random>
#include <thread>

#include "common/image/image_reader.h"
#include "common/net/client.h"
#include "common/transport/photon_record.h"
#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;

class Pipeline : public DemoStoreSuite<Pipeline> {};

TEST_F(Pipeline, TwoWorkersFinishAJobConservingPhotonsAndMatchingOneWorkerBitForBit) {
  const uint64_t photons = 60000;
  nlohmann::json twoStatus, oneStatus;
  {
    LocalCluster cluster(dir_ / "two", 2);
    twoStatus = cluster.render(store_, dir_ / "two.exr", photons, 2);
  }
  ASSERT_EQ(twoStatus.value("state", ""), "done") << twoStatus.dump(2);
  {
    LocalCluster cluster(dir_ / "one", 1);
    oneStatus = cluster.render(store_, dir_ / "one.exr", photons, 2);
  }
  ASSERT_EQ(oneStatus.value("state", ""), "done") << oneStatus.dump(2);

  const auto twoStats = nlohmann::json::parse(readFile(dir_ / "two.exr.json"));
  const auto oneStats = nlohmann::json::parse(readFile(dir_ / "one.exr.json"));
  expectConservation(twoStats);
  expectConservation(oneStats);
  EXPECT_EQ(twoStats["photons"], oneStats["photons"]);
  EXPECT_GT(twoStats["photons"]["crossings"].get<int64_t>(), 0);   // light went through doors
  EXPECT_GT(twoStats["rays"]["crossings"].get<int64_t>(), 0);
  // Short gather rays (lit by rays of their own, cell_kernel.h) are among
  // what must come out the same.
  EXPECT_GT(twoStats["rays"]["gather_short"].get<int64_t>(), 0);
  EXPECT_EQ(twoStats["rays"]["gather_short"], oneStats["rays"]["gather_short"]);
  EXPECT_EQ(twoStats["rays"]["gather"], oneStats["rays"]["gather"]);

  const LinearImage two = readImage((dir_ / "two.exr").string());
  const LinearImage one = readImage((dir_ / "one.exr").string());
  ASSERT_EQ(two.rgb.size(), size_t(96 * 64 * 3));
  ASSERT_EQ(two.rgb.size(), one.rgb.size());
  size_t differing = 0, nonFinite = 0, lit = 0;
  for (size_t i = 0; i < two.rgb.size(); ++i) {
    differing += std::memcmp(&two.rgb[i], &one.rgb[i], sizeof(float)) != 0;
    nonFinite += !std::isfinite(two.rgb[i]);
    lit += two.rgb[i] > 0;
  }
  EXPECT_EQ(differing, 0u);
  EXPECT_EQ(nonFinite, 0u);
  EXPECT_GT(lit, two.rgb.size() / 3);
}


// A worker traces crossings into cells it already holds within the lease
// (worker/lease_runner.cpp, forwardToHeldCells). Handing every crossing back
// instead must give the same bits, and forwarding must actually happen.
TEST_F(Pipeline, TracingCrossingsInHeldCellsChangesNoBit) {
  const uint64_t photons = 60000;
  nlohmann::json forwarding, handedBack;
  {
    LocalCluster cluster(dir_ / "forwarding", 2);
    forwarding = cluster.render(store_, dir_ / "forwarding.exr", photons, 2);
  }
  {
    LocalCluster cluster(dir_ / "handed-back", 2, {{"--forward-rays", "0"}, {"--forward-rays", "0"}});
    handedBack = cluster.render(store_, dir_ / "handed-back.exr", photons, 2);
  }
  ASSERT_EQ(forwarding.value("state", ""), "done") << forwarding.dump(2);
  ASSERT_EQ(handedBack.value("state", ""), "done") << handedBack.dump(2);
  const auto forwardingStats = nlohmann::json::parse(readFile(dir_ / "forwarding.exr.json"));
  const auto handedBackStats = nlohmann::json::parse(readFile(dir_ / "handed-back.exr.json"));
  expectConservation(forwardingStats);
  expectConservation(handedBackStats);
  EXPECT_GT(forwardingStats["rays"]["forwarded"].get<int64_t>(), 0);
  EXPECT_EQ(handedBackStats["rays"]["forwarded"].get<int64_t>(), 0);
  // Forwarding saves round trips, not rays: the same work was done.
  EXPECT_EQ(forwardingStats["photons"], handedBackStats["photons"]);
  EXPECT_EQ(forwardingStats["rays"]["traced"], handedBackStats["rays"]["traced"]);
  EXPECT_EQ(forwardingStats["rays"]["crossings"], handedBackStats["rays"]["crossings"]);
  EXPECT_LT(forwardingStats["leases"].get<int64_t>(), handedBackStats["leases"].get<int64_t>());

  const LinearImage a = readImage((dir_ / "forwarding.exr").string());
  const LinearImage b = readImage((dir_ / "handed-back.exr").string());
  ASSERT_EQ(a.rgb.size(), b.rgb.size());
  EXPECT_EQ(std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * sizeof(float)), 0);
}

// Workers that share the coordinator's file system write their deposits
// into the job's photon file themselves (coordinator/deposit_regions.h).
// The same job with every deposit sent in Results (--no-deposit-regions),
// and with one worker that cannot see the photon file (in a mount namespace
// where a tmpfs hides the cluster's folder) beside one that can, gives the
// same bits.
TEST_F(Pipeline, DepositsWrittenByWorkersIntoThePhotonFileChangeNoBit) {
  const uint64_t photons = 60000;
  nlohmann::json regions, results, mixed;
  {
    LocalCluster cluster(dir_ / "regions", 2);
    regions = cluster.render(store_, dir_ / "regions.exr", photons, 2);
  }
  {
    LocalCluster cluster(dir_ / "results", 2, {}, ClusterOptions{.coordinatorExtra = {"--no-deposit-regions"}});
    results = cluster.render(store_, dir_ / "results.exr", photons, 2);
  }
  const bool namespaces = runCommand({"/usr/bin/unshare", "-m", "/bin/true"}, dir_ / "unshare.log") == 0;
  if (namespaces) {
    const fs::path hidden = dir_ / "mixed";
    LocalCluster cluster(hidden, 1);
    cluster.addWorker({}, [&](std::vector<std::string> argv) {
      std::string command = "mount -t tmpfs none '" + hidden.string() + "' && exec";
      for (const std::string& a : argv) command += " '" + a + "'";
      return std::vector<std::string>{"/usr/bin/unshare", "-m", "/bin/sh", "-c", command};
    });
    mixed = cluster.render(store_, dir_ / "mixed.exr", photons, 2);
    ASSERT_EQ(mixed.value("state", ""), "done") << mixed.dump(2);
  }
  ASSERT_EQ(regions.value("state", ""), "done") << regions.dump(2);
  ASSERT_EQ(results.value("state", ""), "done") << results.dump(2);
  const auto regionStats = nlohmann::json::parse(readFile(dir_ / "regions.exr.json"));
  const auto resultStats = nlohmann::json::parse(readFile(dir_ / "results.exr.json"));
  expectConservation(regionStats);
  EXPECT_EQ(regionStats["photons"], resultStats["photons"]);
  const auto bytesOf = [](const nlohmann::json& stats, const char* key) { return stats["disk"][key].get<int64_t>(); };
  const int64_t depositBytes = regionStats["photons"]["deposits"].get<int64_t>() * int64_t(sizeof(PhotonRecord));
  EXPECT_GT(bytesOf(regionStats, "photon_bytes_from_workers"), depositBytes / 2);
  EXPECT_EQ(bytesOf(regionStats, "photon_bytes_from_workers") + bytesOf(regionStats, "photon_bytes_from_results"),
            bytesOf(resultStats, "photon_bytes_from_results"));
  EXPECT_EQ(bytesOf(resultStats, "photon_bytes_from_workers"), 0);
  // The render phase's photon tables: read by the workers from the photon
  // file, none sent through the coordinator.
  EXPECT_GT(bytesOf(regionStats, "photon_tables_read_by_workers"), 0);
  EXPECT_EQ(bytesOf(regionStats, "photon_bytes_sent"), 0);
  EXPECT_EQ(differingFloats(dir_ / "regions.exr", dir_ / "results.exr"), 0u);
  if (!namespaces) GTEST_SKIP() << "cannot create a mount namespace here (unshare -m): " << readFile(dir_ / "unshare.log");
  const auto mixedStats = nlohmann::json::parse(readFile(dir_ / "mixed.exr.json"));
  EXPECT_EQ(mixedStats["photons"], resultStats["photons"]);
  EXPECT_GT(bytesOf(mixedStats, "photon_bytes_from_workers"), 0);
  EXPECT_GT(bytesOf(mixedStats, "photon_bytes_from_results"), 0);
  EXPECT_NE(readFile(dir_ / "mixed" / "worker-1.log").find("deposits go in the results"), std::string::npos);
  // The worker that cannot see the photon file asks for its tables' bytes.
  EXPECT_GT(bytesOf(mixedStats, "photon_bytes_sent"), 0);
  EXPECT_NE(readFile(dir_ / "mixed" / "worker-1.log").find("cannot read the photon file"), std::string::npos);
  EXPECT_EQ(differingFloats(dir_ / "regions.exr", dir_ / "mixed.exr"), 0u);
}

TEST_F(Pipeline, WorkersThatCrashMidLeaseChangeNoBit) {
  const uint64_t photons = 60000;
  nlohmann::json reference, crashed;
  {
    LocalCluster cluster(dir_ / "reference", 1);
    reference = cluster.render(store_, dir_ / "reference.exr", photons, 1);
  }
  {
    // Two of three workers die holding a finished lease (their 2nd and 5th).
    LocalCluster cluster(dir_ / "crash", 3, {{"--crash-after-leases", "2"}, {"--crash-after-leases", "5"}, {}});
    crashed = cluster.render(store_, dir_ / "crash.exr", photons, 1);
  }
  ASSERT_EQ(reference.value("state", ""), "done") << reference.dump(2);
  ASSERT_EQ(crashed.value("state", ""), "done") << crashed.dump(2);
  EXPECT_NE(readFile(dir_ / "crash" / "coordinator.log").find("requeued"), std::string::npos);
  const auto stats = nlohmann::json::parse(readFile(dir_ / "crash.exr.json"));
  expectConservation(stats);
  EXPECT_EQ(stats["photons"], nlohmann::json::parse(readFile(dir_ / "reference.exr.json"))["photons"]);
  EXPECT_EQ(differingFloats(dir_ / "crash.exr", dir_ / "reference.exr"), 0u);
}

// A commit that fails (a full disk) loses nothing: the coordinator sends
// nothing of that round, forgets the leases it opened and requeues those
// whose Results it applied, which are traced again with the same bits.
TEST_F(Pipeline, FailedCommitsLoseNothingAndChangeNoBit) {
  const uint64_t photons = 60000;
  nlohmann::json reference, failing;
  {
    LocalCluster cluster(dir_ / "commit-reference", 1);
    reference = cluster.render(store_, dir_ / "commit-reference.exr", photons, 1);
  }
  {
    ClusterOptions options;
    options.coordinatorExtra = {"--fail-commits-every", "4"};
    LocalCluster cluster(dir_ / "commit-failing", 2, {}, options);
    failing = cluster.render(store_, dir_ / "commit-failing.exr", photons, 1);
  }
  ASSERT_EQ(reference.value("state", ""), "done") << reference.dump(2);
  ASSERT_EQ(failing.value("state", ""), "done") << failing.dump(2);
  const std::string log = readFile(dir_ / "commit-failing" / "coordinator.log");
  EXPECT_NE(log.find("fault injection: this commit fails"), std::string::npos);
  const auto stats = nlohmann::json::parse(readFile(dir_ / "commit-failing.exr.json"));
  expectConservation(stats);
  EXPECT_EQ(stats["photons"], nlohmann::json::parse(readFile(dir_ / "commit-reference.exr.json"))["photons"]);
  EXPECT_EQ(differingFloats(dir_ / "commit-failing.exr", dir_ / "commit-reference.exr"), 0u);
}

TEST_F(Pipeline, ACoordinatorKilledMidJobResumesFromJobsDbWithTheSameBits) {
  const uint64_t photons = 60000;
  {
    LocalCluster cluster(dir_ / "restart-reference", 1);
    ASSERT_EQ(cluster.render(store_, dir_ / "restart-reference.exr", photons, 1).value("state", ""), "done");
  }
  LocalCluster cluster(dir_ / "restart", 2);
  const std::string endpoint = cluster.endpoint();   // the restart binds the same port
  const uint64_t job = cluster.submit(store_, dir_ / "restart.exr", photons, 1);
  // Kill it once work is under way (some leases done, the job unfinished).
  for (int i = 0; i < 400; ++i) {
    const auto status = cluster.status(job);
    if (status["leases"].get<int64_t>() >= 3 || status.value("state", "") != "photons") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  cluster.killCoordinator();
  cluster.startCoordinator(endpoint);
  const auto status = cluster.wait(job);
  ASSERT_EQ(status.value("state", ""), "done") << status.dump(2);
  EXPECT_NE(readFile(dir_ / "restart" / "coordinator.log").find("requeued"), std::string::npos);
  const auto stats = nlohmann::json::parse(readFile(dir_ / "restart.exr.json"));
  expectConservation(stats);
  EXPECT_EQ(stats["photons"],
            nlohmann::json::parse(readFile(dir_ / "restart-reference.exr.json"))["photons"]);
  EXPECT_EQ(differingFloats(dir_ / "restart.exr", dir_ / "restart-reference.exr"), 0u);
}

TEST_F(Pipeline, EveryPorticoAcceleratorGivesTheSameBits) {
  // One watertight triangle test and one tie-break: the photons stored and
  // the image are identical whatever structure each cell uses — in rooms,
  // and in voxel cells cut by a uniform grid, whose triangles stick out.
  const fs::path voxels = dir_ / "two_rooms_grid3";
  ASSERT_EQ(importVoxelStore("two_rooms", 3, voxels), "");
  const std::vector<std::string> specs{"grid",    "grid:res=7", "hgrid:res=4,max=8", "kd:median", "kd:sah", "kd:bbox",
                                       "bvh",     "bvh:width=4", "brute",             "auto"};
  for (const fs::path& store : {store_, voxels}) {
    auto imageOf = [&](size_t i) { return dir_ / (store.filename().string() + "-accel" + std::to_string(i) + ".exr"); };
    for (size_t i = 0; i < specs.size(); ++i) {
      const fs::path log = dir_ / ("accel" + std::to_string(i) + ".log");
      ASSERT_EQ(runCommand({kBin + "portico", "render", store.string(), "-o", imageOf(i).string(), "--workers", "2",
                            "--accel", specs[i], "--photons", "20000", "--spp", "1", "--gather", "2", "--width", "64",
                            "--height", "48"},
                           log),
                0)
          << readFile(log);
      if (i == 0) continue;
      EXPECT_EQ(differingFloats(imageOf(i), imageOf(0)), 0u) << specs[i] << " on " << store;
      const auto a = nlohmann::json::parse(readFile(fs::path(imageOf(i).string() + ".json")));
      const auto b = nlohmann::json::parse(readFile(fs::path(imageOf(0).string() + ".json")));
      EXPECT_EQ(a["photons"], b["photons"]) << specs[i] << " on " << store;
    }
  }
}

TEST_F(Pipeline, AutoPicksPerCellRebuildsBusyCellsAndKeepsTheBits) {
  // A calibration under which a grid is free to build and slow to trace and
  // kd:sah costs 5 ms to build and traces 10x faster: cells start with a grid
  // while few rays are expected, and the busy ones are rebuilt as kd-trees
  // once the rays they keep taking pay for the build. Neither changes a bit.
  nlohmann::json families;
  for (const char* family : {"hgrid", "kd:median", "kd:bbox", "bvh"})
    families[family] = {{"build", {1e6, 0, 0}}, {"trace", {1e6, 0}}};
  families["grid"] = {{"build", {0, 0, 0}}, {"trace", {1000, 0, 0}}};
  families["kd:sah"] = {{"build", {5, 0, 0}}, {"trace", {100, 0}}};
  const fs::path calibration = dir_ / "calibration.json";
  std::ofstream(calibration) << nlohmann::json{{"version", 1}, {"origin", "test"}, {"families", families}}.dump();
  ::setenv("PORTICO_CALIBRATION", calibration.c_str(), 1);
  auto render = [&](const std::string& accel, const fs::path& image) {
    const fs::path log = fs::path(image.string() + ".log");
    EXPECT_EQ(runCommand({kBin + "portico", "render", store_.string(), "-o", image.string(), "--workers", "2",
                          "--accel", accel, "--photons", "40000", "--spp", "1", "--gather", "4", "--width", "64",
                          "--height", "48"},
                         log),
              0)
        << readFile(log);
    return nlohmann::json::parse(readFile(fs::path(image.string() + ".json")));
  };
  const auto chosen = render("auto", dir_ / "auto.exr");
  ::unsetenv("PORTICO_CALIBRATION");
  const auto fixed = render("grid", dir_ / "auto-reference.exr");
  EXPECT_EQ(differingFloats(dir_ / "auto.exr", dir_ / "auto-reference.exr"), 0u);
  EXPECT_EQ(chosen["photons"], fixed["photons"]);
  // Every loaded cell is listed with what it was built with; some started
  // as grids and were rebuilt as kd-trees.
  const auto& cells = chosen["cell_accelerators"];
  ASSERT_TRUE(cells.is_object()) << chosen.dump(2);
  EXPECT_GT(cells.size(), 0u);
  int rebuilt = 0;
  for (const auto& [cell, specs] : cells.items()) {
    bool grid = false, kd = false;
    for (const auto& spec : specs) {
      const std::string name = spec.get<std::string>();
      const bool isGrid = name == "grid" || name.rfind("grid:res=", 0) == 0;
      grid |= isGrid;
      kd |= name == "kd:sah";
      // The photon pass picks grid or kd:sah; render leases trace with bvh
      // (the automatic render structure with --accel auto).
      EXPECT_TRUE(isGrid || name == "kd:sah" || name == "bvh") << spec;
    }
    rebuilt += grid && kd;
  }
  EXPECT_GT(rebuilt, 0) << cells.dump();
  EXPECT_GT(chosen["accelerators"].value("kd:sah", 0), 0) << chosen["accelerators"].dump();
}

TEST_F(Pipeline, RenderCommandWritesImageAndStatistics) {
  const fs::path output = dir_ / "render.png";
  ASSERT_EQ(runCommand({kBin + "portico", "render", store_.string(), "-o", output.string(), "--workers", "2",
                        "--photons", "20000", "--spp", "1", "--width", "48", "--height", "32"},
                       dir_ / "render.log"),
            0)
      << readFile(dir_ / "render.log");
  const LinearImage image = readImage(output.string());
  EXPECT_EQ(image.width, 48u);
  EXPECT_EQ(image.height, 32u);
  const auto stats = nlohmann::json::parse(readFile(fs::path(output.string() + ".json")));
  expectConservation(stats);
  for (const char* key : {"emitted", "deposits", "absorbed", "escaped", "queued"})
    EXPECT_TRUE(stats["photons"].contains(key)) << key;
  EXPECT_TRUE(stats["time_ms"].contains("photons"));
  EXPECT_TRUE(stats["time_ms"].contains("render"));
  // The workers' time in leases: more than nothing, less than both workers
  // busy for the whole job.
  const int64_t leases = stats["time_ms"].value("leases", int64_t(-1));
  EXPECT_GT(leases, 0);
  EXPECT_LE(leases, 2 * stats["time_ms"]["total"].get<int64_t>());
  EXPECT_GT(stats["cells"]["loaded"].get<int64_t>(), 0);
}

TEST_F(Pipeline, SubmitStatusAndWaitWorkAgainstServicesStartedByHand) {
  const fs::path dir = dir_ / "cli";
  LocalCluster cluster(dir, 2);
  int code = -1;
  const std::string id =
      captureOutput({kBin + "portico", "submit", "--coordinator", cluster.endpoint(), store_.string(), "-o",
                     (dir / "cli.png").string(), "--photons", "20000", "--spp", "1", "--width", "40", "--height", "30"},
                    dir, "submit", &code);
  ASSERT_EQ(code, 0) << readFile(dir / "submit.log");
  const uint64_t job = std::stoull(id);
  EXPECT_GT(job, 0u);
  EXPECT_EQ(runCommand({kBin + "portico", "wait", "--coordinator", cluster.endpoint(), std::to_string(job)},
                       dir / "wait.log"),
            0)
      << readFile(dir / "wait.log");
  const std::string json = captureOutput(
      {kBin + "portico", "status", "--coordinator", cluster.endpoint(), std::to_string(job), "--json"}, dir, "status",
      &code);
  ASSERT_EQ(code, 0);
  const auto status = nlohmann::json::parse(json);
  EXPECT_EQ(status.value("state", ""), "done");
  EXPECT_EQ(status["progress"].value("fraction", 0.0), 1.0);
  EXPECT_EQ(status["workers"].size(), 2u);
  EXPECT_TRUE(fs::exists(dir / "cli.png"));
  // Waiting on a job that does not exist fails with a message naming it.
  EXPECT_NE(runCommand({kBin + "portico", "wait", "--coordinator", cluster.endpoint(), "999"}, dir / "wait999.log"), 0);
  EXPECT_NE(readFile(dir / "wait999.log").find("999"), std::string::npos);
}

TEST_F(Pipeline, CancelStopsAJobAndWaitReportsIt) {
  const fs::path dir = dir_ / "cancel";
  LocalCluster cluster(dir, 1);
  const uint64_t job = cluster.submit(store_, dir / "cancelled.png", 50000000, 1);
  ASSERT_EQ(runCommand({kBin + "portico", "cancel", "--coordinator", cluster.endpoint(), std::to_string(job)},
                       dir / "cancel.log"),
            0)
      << readFile(dir / "cancel.log");
  EXPECT_NE(runCommand({kBin + "portico", "wait", "--coordinator", cluster.endpoint(), std::to_string(job)},
                       dir / "wait.log"),
            0);
  const auto status = cluster.status(job);
  EXPECT_EQ(status.value("state", ""), "cancelled");
  EXPECT_EQ(status["photons"]["queued"].get<int64_t>(), 0);   // its queues are dropped
  EXPECT_FALSE(fs::exists(dir / "cancelled.png"));
}

TEST_F(Pipeline, ACorruptCellFileFailsTheJobNamingTheCellAndNothingCrashes) {
  const fs::path dir = dir_ / "corrupt";
  const fs::path store = dir / "store";
  fs::create_directories(dir);
  fs::copy(store_, store, fs::copy_options::recursive);
  // Cell 5 (the dark room) gets garbage bytes of a plausible size.
  {
    std::ofstream cell(store / "cells" / "5.cell", std::ios::binary | std::ios::trunc);
    std::mt19937 random(1);
    for (int i = 0; i < 4096; ++i) cell.put(static_cast<char>(random()));
  }
  LocalCluster cluster(dir, 2);
  const auto status = cluster.render(store, dir / "never.png", 20000, 1);
  EXPECT_EQ(status.value("state", ""), "failed") << status.dump(2);
  const std::string error = status.value("error", "");
  EXPECT_NE(error.find("cell 5"), std::string::npos) << error;
  EXPECT_NE(error.find("5.cell"), std::string::npos) << error;
  EXPECT_NE(error.find("failed 3 times"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(dir / "never.png"));
  // The coordinator still serves: a good job on the same cluster finishes.
  EXPECT_EQ(cluster.render(store_, dir / "after.png", 5000, 1).value("state", ""), "done");
}

TEST_F(Pipeline, RefusesAJobForAMissingStoreWithAClearMessage) {
  LocalCluster cluster(dir_ / "refuse", 0);
  net::CoordinatorClient client(cluster.endpoint());
  capnp::MallocMessageBuilder message;
  auto spec = message.initRoot<wire::Envelope>().initSubmit().initSpec();
  spec.setStore((dir_ / "no-such-store").string());
  spec.setOutput((dir_ / "x.png").string());
  spec.setPhotons(10);
  spec.setSpp(1);
  spec.setPhotonRadius(0.5f);
  try {
    client.submit(message);
    FAIL() << "submit should have been refused";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no-such-store"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace portico
