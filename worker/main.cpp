// portico-worker: loads cells, builds accelerators and traces the rays the
// coordinator leases to it.
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <csignal>
#include <cstdlib>
#include <cstdint>
#include <thread>

#include "common/accel/embree_accelerator.h"
#include "common/job/worker_tags.h"
#include "common/transport/albedo_texture.h"
#include "common/util/cli_bounds.h"
#include "common/util/heap_reuse.h"
#include "common/util/size_parse.h"
#include "worker/worker_session.h"

namespace {
portico::WorkerSession* running = nullptr;
void onSignal(int) {
  if (running) running->stop();
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"portico-worker: traces portico cell leases"};
  portico::WorkerOptions options;
  std::string memory = "2GiB", logLevel = "info";
  char host[256] = {0};
  gethostname(host, sizeof host - 1);
  options.name = std::string(host) + ":" + std::to_string(getpid());
  app.add_option("--connect", options.connect, "coordinator endpoint")->capture_default_str();
  app.add_option("--memory", memory, "the whole worker's memory: its code, and a cache for cells, accelerators, photon maps and texture tiles (e.g. 512MiB, 4GiB)")
      ->capture_default_str()
      ->check(portico::cli::workerMemory());
  app.add_option("--threads", options.threads, "tracing threads")
      ->capture_default_str()
      ->check(portico::cli::wholeNumber(1, 1024));
  app.add_option("--name", options.name, "name shown in status");
  app.add_option("--tag", options.tags,
                 "a pool this worker belongs to (repeatable): jobs submitted with --require NAME are leased only to "
                 "workers having every tag they require; names of letters, digits, '-', '_', '.' (default: "
                 "$PORTICO_WORKER_TAGS, names split at commas or spaces, as the deploy templates set it)")
      ->check(CLI::Validator([](std::string& tag) { return portico::tagNameProblem(tag); }, "NAME"));
  app.add_option("--heartbeat-ms", options.heartbeatMs)->capture_default_str()->check(portico::cli::wholeNumber(1, 600000));
  app.add_option("--liveness-ms", options.livenessMs)->capture_default_str()->check(portico::cli::wholeNumber(1, 86400000));
  app.add_option("--crash-after-leases", options.crashAfterLeases, "fault injection: exit without reporting the Nth lease")
      ->check(portico::cli::wholeNumber(0, INT32_MAX));
  app.add_option("--crash-in-lease", options.crashInLease,
                 "fault injection: crash (SIGSEGV) tracing the Nth lease, as a cell that crashes its worker would")
      ->check(portico::cli::wholeNumber(0, INT32_MAX));
  app.add_option("--keys", options.keysDirectory,
                 "CURVE keys directory (`portico keys generate`): coordinator.public, worker.secret (default on tcp://: "
                 "the per-user keys, ~/.config/portico/keys or $PORTICO_KEYS, when they exist)")
      ->check(CLI::ExistingDirectory);
  app.add_option("--cache-dir", options.cacheDirectory,
                 "fetch scene stores from the coordinator into this disk cache (no shared file system needed)");
  app.add_option("--calibration", options.calibrationPath,
                 "the accelerator cost model's calibration for --accel auto (`portico bench calibrate`; default: "
                 "$PORTICO_CALIBRATION, else ~/.cache/portico/calibration.json when present, else built-in)");
  app.add_option("--forward-rays", options.forwardRays,
                 "most rays a lease traces in neighbour cells this worker already holds, instead of handing them "
                 "back (at least the lease's own work; 0: hand every crossing back)")
      ->capture_default_str()
      ->check(portico::cli::wholeNumber(0, INT64_MAX));
  app.add_option("--lease-limit-s", options.leaseLimitSeconds,
                 "a lease still tracing after this many seconds is failed and the worker exits: its thread is stuck "
                 "(a read that never returns, on a hung file system)")
      ->capture_default_str()
      ->check(portico::cli::wholeNumber(1, 86400 * 7));
  app.add_option("--log-level", logLevel)->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  spdlog::set_level(spdlog::level::from_str(logLevel));
  spdlog::set_pattern(fmt::format("[%H:%M:%S.%e] [worker {}] [%l] %v", options.name));
  try {
    options.memoryBytes = portico::parseByteSize(memory);
    // The deploy templates (systemd, Kubernetes, Slurm, Docker) give a
    // worker's pools in the environment, where a repeated option is awkward.
    if (const char* given = std::getenv("PORTICO_WORKER_TAGS"); options.tags.empty() && given) {
      std::string name;
      for (const char* c = given;; ++c) {
        if (*c == '\0' || *c == ',' || std::isspace(static_cast<unsigned char>(*c))) {
          if (!name.empty()) options.tags.push_back(name);
          name.clear();
          if (*c == '\0') break;
        } else {
          name += *c;
        }
      }
      for (const std::string& tag : options.tags)
        if (const std::string problem = portico::tagNameProblem(tag); !problem.empty())
          throw std::invalid_argument("PORTICO_WORKER_TAGS: " + problem);
    }
    options.tags = portico::normalizedTags(options.tags, "--tag");
    // Free memory kept for the next lease: an eighth of the cache budget,
    // at most 256 MiB, so resident memory still follows the budget. On the
    // octagon photon pass (1 M photons, 1 worker) this cut page faults from
    // 400 K to 162 K and CPU by about 10 % (docs/pipeline-benchmark.md).
    portico::keepFreedMemory(std::clamp<uint64_t>(options.memoryBytes / 8, 1 << 20, uint64_t(256) << 20));
    // Texture tiles, for stores with textured materials: a sixteenth of the
    // budget, 4 to 256 MiB, taken from the cell cache when a texture is met.
    portico::AlbedoTextures::instance().setCacheBytes(
        std::clamp<uint64_t>(options.memoryBytes / 16, uint64_t(4) << 20, uint64_t(256) << 20));
    // A worker owns --threads cores: Embree's builds (--accel embree) run on
    // as many, not on every core of the machine, which two workers on two
    // cores would each take (octagon photon pass, 2 workers: 2.1 s of
    // builds, against 1.2 s with one worker).
    portico::configureEmbreeDevice(fmt::format("threads={}", std::max(1u, options.threads)));
    portico::WorkerSession session(options);
    running = &session;
    std::signal(SIGINT, onSignal);
    std::signal(SIGTERM, onSignal);
    const int code = session.run();
    running = nullptr;
    return code;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
}
