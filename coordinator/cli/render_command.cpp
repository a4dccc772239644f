// `portico render`: everything on this machine. Starts a coordinator on an
// ipc:// socket in a private directory (mode 0700: no other user can reach
// it) with a private jobs.db, N workers, submits the job, shows progress,
// and stops the services when the job ends or on Ctrl-C.
#include <capnp/message.h>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <signal.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <thread>

#include "common/net/client.h"
#include "common/util/child_process.h"
#include "coordinator/cli/commands.h"
#include "coordinator/cli/progress.h"

namespace portico::cli {

void fillSubmit(const JobSettings& o, capnp::MallocMessageBuilder& message);

namespace {
volatile sig_atomic_t interrupted = 0;
void onInterrupt(int) { interrupted = 1; }

std::string readEndpoint(const std::string& path, ChildProcess& coordinator, const std::string& log) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (std::chrono::steady_clock::now() < deadline) {
    std::ifstream in(path);
    std::string endpoint;
    if (in >> endpoint && !endpoint.empty()) return endpoint;
    if (!coordinator.running())
      throw std::runtime_error(fmt::format("the coordinator exited (status {}) before listening; see {}",
                                           coordinator.exitCode(), log));
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  throw std::runtime_error(fmt::format("the coordinator did not start listening within 20 s; see {}", log));
}
}  // namespace

int runRender(const JobSettings& render, const LocalRunOptions& local) {
  if (local.workers == 0) throw std::invalid_argument("--workers must be at least 1");
  capnp::MallocMessageBuilder submit;
  fillSubmit(render, submit);   // validates options before anything starts

  char pattern[] = "/tmp/portico-render-XXXXXX";
  if (!mkdtemp(pattern)) throw std::runtime_error("cannot create a temporary directory under /tmp");
  const std::filesystem::path work(pattern);
  const std::string coordinatorLog = (work / "coordinator.log").string();
  const std::string endpointFile = (work / "endpoint").string();

  // --keys goes to every child, and to this process's own client.
  std::vector<std::string> keys;
  if (!local.keys.empty()) keys = {"--keys", std::filesystem::absolute(local.keys).string()};
  // mkdtemp made the directory 0700: the socket in it is this user's alone.
  // A socket file whose name is known before the coordinator starts: the
  // workers start beside it instead of after it has bound (its start-up,
  // most of it loading shared libraries, is about a third of a small
  // render's wall time), and ZeroMQ connects them once it listens.
  const std::string endpoint = "ipc://" + (work / "coordinator.ipc").string();
  std::vector<std::string> coordinatorArgv{findProgram("portico-coordinator"), "--listen", endpoint, "--db",
                                           (work / "jobs.db").string(), "--endpoint-file", endpointFile,
                                           "--log-level", local.logLevel};
  coordinatorArgv.insert(coordinatorArgv.end(), keys.begin(), keys.end());
  ChildProcess coordinator(coordinatorArgv, coordinatorLog);
  std::vector<ChildProcess> workers;
  const std::string workerProgram = findProgram("portico-worker");
  for (uint32_t i = 0; i < local.workers; ++i) {
    std::vector<std::string> argv{workerProgram, "--connect", endpoint, "--memory", local.memory,
                                  "--name", fmt::format("local-{}", i), "--log-level", local.logLevel};
    argv.insert(argv.end(), keys.begin(), keys.end());
    workers.emplace_back(argv, (work / fmt::format("worker-{}.log", i)).string());
  }

  readEndpoint(endpointFile, coordinator, coordinatorLog);   // it listens: submit

  signal(SIGINT, onInterrupt);
  signal(SIGTERM, onInterrupt);
  net::CoordinatorClient client(endpoint, local.keys);
  const uint64_t job = client.submit(submit);
  ProgressDisplay display(false);
  std::string state;
  nlohmann::json status;
  while (!interrupted) {
    try {
      status = nlohmann::json::parse(client.statusJson(job));
    } catch (const zmq::error_t& e) {
      if (e.num() == EINTR) continue;   // Ctrl-C: the loop condition decides
      throw;
    }
    display.update(status);
    state = status.value("state", "");
    if (state == "done" || state == "failed" || state == "cancelled") break;
    if (!coordinator.running()) {
      state = "failed";
      status["error"] = fmt::format("the coordinator exited (status {}); see {}", coordinator.exitCode(), coordinatorLog);
      break;
    }
    size_t alive = 0;
    for (ChildProcess& w : workers) alive += w.running();
    if (alive == 0) {
      state = "failed";
      status["error"] = fmt::format("every worker exited; see the logs in {}", work.string());
      break;
    }
    // Polled often: a small render ends within a second, and waiting a
    // longer period after it adds to every run.
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  if (interrupted) {
    // A terminal's Ctrl-C reached the services too, and the coordinator may
    // be gone already: a short try, then stop them whatever it answered.
    try {
      net::CoordinatorClient(endpoint, local.keys, std::chrono::seconds(1)).cancel(job);
    } catch (const std::exception&) {
    }
    state = "cancelled";
    status["error"] = "interrupted";
  }
  display.finish(status);
  for (ChildProcess& w : workers) w.kill(SIGTERM);
  for (ChildProcess& w : workers) w.stop(std::chrono::seconds(2));
  coordinator.stop(std::chrono::seconds(5));
  const bool ok = state == "done";
  if (ok && !local.keepLogs)
    std::filesystem::remove_all(work);
  else
    std::cerr << fmt::format("logs and jobs.db kept in {}\n", work.string());
  return ok ? 0 : 1;
}

}  // namespace portico::cli
