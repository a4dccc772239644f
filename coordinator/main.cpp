// portico-coordinator: owns jobs.db and schedules cell leases on workers.
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <csignal>

#include "common/util/cli_bounds.h"
#include "common/util/heap_reuse.h"
#include "coordinator/coordinator.h"

namespace {
portico::Coordinator* running = nullptr;
void onSignal(int) {
  if (running) running->stop();
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"portico-coordinator: schedules cell work on portico workers"};
  portico::CoordinatorOptions options;
  std::string logLevel = "info";
  app.add_option("--listen", options.listen,
                 "ZeroMQ endpoint to bind: tcp://HOST:PORT (loopback by default; port * picks one) or ipc://PATH")
      ->capture_default_str();
  app.add_option("--db", options.database, "job database (SQLite, created if missing)")->capture_default_str();
  app.add_option("--endpoint-file", options.endpointFile, "write the bound endpoint to this file");
  app.add_option("--heartbeat-ms", options.heartbeatMs, "heartbeat interval")
      ->capture_default_str()
      ->check(portico::cli::wholeNumber(1, 600000));
  app.add_option("--liveness-ms", options.livenessMs, "silence after which a worker is presumed dead")
      ->capture_default_str()
      ->check(portico::cli::wholeNumber(1, 86400000));
  // The frame limit grows with it (2 KiB per ray): 10^6 rays is 2 GiB.
  app.add_option("--lease-rays", options.maxLeaseWork, "rays per lease")
      ->capture_default_str()
      ->check(portico::cli::wholeNumber(1, 1000000));
  app.add_option("--max-cell-failures", options.maxCellFailures,
                 "failures a worker reports for one cell before its job fails")
      ->capture_default_str()
      ->check(portico::cli::wholeNumber(1, 1000));
  app.add_option("--max-lost-leases", options.maxLostLeases,
                 "times one cell's lease may be lost with its worker (killed, out of memory, gone) before its job fails")
      ->capture_default_str()
      ->check(portico::cli::wholeNumber(1, 1000));
  double storeGoneSeconds = double(options.storeGoneTimeoutMs) / 1000;
  app.add_option("--store-gone-timeout", storeGoneSeconds,
                 "seconds a job waits for its scene store to be readable again (deleted, moved, unmounted) before "
                 "it fails saying so")
      ->capture_default_str()
      ->check(portico::cli::realNumber(0.001, 1e9));
  double leaseTimeoutSeconds = double(options.leaseTimeoutMs) / 1000;
  app.add_option("--lease-timeout-s", leaseTimeoutSeconds,
                 "seconds a worker may hold leases with no progress (no Result, and heartbeats saying its tracing did "
                 "not move: a read that never returns) before they are taken back and traced by other workers")
      ->capture_default_str()
      ->check(portico::cli::realNumber(0.1, 1e7));
  app.add_option("--keys", options.keysDirectory,
                 "CURVE keys directory (`portico keys generate`): encrypt, and admit only the keys of "
                 "{client,worker,operator}.public, each in its role; required beyond loopback. Without it, "
                 "tcp:// uses this user's keys (~/.config/portico/keys or $PORTICO_KEYS, written on first use) "
                 "and ipc:// admits only this user and root")
      ->check(CLI::ExistingDirectory);
  bool noDepositRegions = false;
  app.add_flag("--no-deposit-regions", noDepositRegions,
               "workers send every deposit in their Results, even those that could write them into the job's "
               "photon file themselves (docs/architecture.md, deposit regions)");
  app.add_option("--fail-commits-every", options.failCommitsEvery,
                 "fault injection: every Nth transaction applying Results fails to commit, as on a full disk");
  app.add_option("--log-level", logLevel, "trace, debug, info, warn, error")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  options.depositRegions = !noDepositRegions;
  options.storeGoneTimeoutMs = static_cast<int64_t>(storeGoneSeconds * 1000);
  options.leaseTimeoutMs = static_cast<int64_t>(leaseTimeoutSeconds * 1000);
  spdlog::set_level(spdlog::level::from_str(logLevel));
  spdlog::set_pattern("[%H:%M:%S.%e] [coordinator] [%l] %v");
  // Each job's recent lines, for `portico dashboard` (coordinator/job_log.h).
  options.jobLog = std::make_shared<portico::JobLog>();
  spdlog::default_logger()->sinks().push_back(options.jobLog);
  // Every Result is unpacked into fresh segments and its batches re-packed:
  // keep what they free (a bounded amount, whatever the queues hold).
  portico::keepFreedMemory(uint64_t(256) << 20);
  try {
    portico::Coordinator coordinator(options);
    running = &coordinator;
    std::signal(SIGINT, onSignal);
    std::signal(SIGTERM, onSignal);
    coordinator.run();
    running = nullptr;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
  return 0;
}
