#include "coordinator/cli/local_services.h"

#include <fmt/format.h>
#include <signal.h>
#include <stdlib.h>

#include <chrono>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <thread>

#include "common/util/temporary_directory.h"

namespace portico::cli {

namespace {
volatile sig_atomic_t interruptedFlag = 0;
void onInterrupt(int) { interruptedFlag = 1; }

void waitForEndpoint(const std::string& path, ChildProcess& coordinator, const std::string& log) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (std::chrono::steady_clock::now() < deadline) {
    std::ifstream in(path);
    std::string endpoint;
    if (in >> endpoint && !endpoint.empty()) return;
    if (!coordinator.running())
      throw std::runtime_error(fmt::format("the coordinator exited (status {}) before listening; see {}",
                                           coordinator.exitCode(), log));
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  throw std::runtime_error(fmt::format("the coordinator did not start listening within 20 s; see {}", log));
}
}  // namespace

void catchInterrupts() {
  signal(SIGINT, onInterrupt);
  signal(SIGTERM, onInterrupt);
}

bool interrupted() { return interruptedFlag != 0; }

LocalServices::LocalServices(const LocalRunOptions& local) {
  if (local.workers == 0) throw std::invalid_argument("--workers must be at least 1");
  // Under $TMPDIR, else /tmp: jobs.db and the job's photon files go there,
  // hundreds of megabytes for a large pass.
  work_ = makeTemporaryDirectory("portico-render");
  coordinatorLog_ = (work_ / "coordinator.log").string();
  const std::string endpointFile = (work_ / "endpoint").string();

  // --keys goes to every child, and to this process's own client.
  std::vector<std::string> keys;
  if (!local.keys.empty()) {
    keys_ = std::filesystem::absolute(local.keys).string();
    keys = {"--keys", keys_};
  }
  // mkdtemp made the directory 0700: the socket in it is this user's alone.
  // A socket file whose name is known before the coordinator starts: the
  // workers start beside it instead of after it has bound (its start-up,
  // most of it loading shared libraries, is about a third of a small
  // render's wall time), and ZeroMQ connects them once it listens.
  endpoint_ = "ipc://" + (work_ / "coordinator.ipc").string();
  std::vector<std::string> coordinatorArgv{findProgram("portico-coordinator"), "--listen", endpoint_, "--db",
                                           (work_ / "jobs.db").string(), "--endpoint-file", endpointFile,
                                           "--log-level", local.logLevel};
  coordinatorArgv.insert(coordinatorArgv.end(), keys.begin(), keys.end());
  coordinator_.emplace(coordinatorArgv, coordinatorLog_);
  const std::string workerProgram = findProgram("portico-worker");
  for (uint32_t i = 0; i < local.workers; ++i) {
    std::vector<std::string> argv{workerProgram, "--connect", endpoint_, "--memory", local.memory,
                                  "--name", fmt::format("local-{}", i), "--log-level", local.logLevel};
    argv.insert(argv.end(), keys.begin(), keys.end());
    workers_.emplace_back(argv, (work_ / fmt::format("worker-{}.log", i)).string());
  }
  waitForEndpoint(endpointFile, *coordinator_, coordinatorLog_);
}

// Left by an exception (a job refused at submit, which said why): nothing
// in the directory is worth keeping.
LocalServices::~LocalServices() {
  if (stopped_) return;
  try {
    stop(false);
  } catch (const std::exception&) {
  }
}

std::optional<std::string> LocalServices::failure() {
  if (!coordinator_->running())
    return fmt::format("the coordinator exited (status {}); see {}", coordinator_->exitCode(), coordinatorLog_);
  size_t alive = 0;
  for (ChildProcess& w : workers_) alive += w.running();
  if (alive == 0) return fmt::format("every worker exited; see the logs in {}", work_.string());
  return std::nullopt;
}

void LocalServices::stop(bool keep) {
  stopped_ = true;
  for (ChildProcess& w : workers_) w.kill(SIGTERM);
  for (ChildProcess& w : workers_) w.stop(std::chrono::seconds(2));
  coordinator_->stop(std::chrono::seconds(5));
  if (!keep)
    std::filesystem::remove_all(work_);
  else
    std::cerr << fmt::format("logs and jobs.db kept in {}\n", work_.string());
}

}  // namespace portico::cli
