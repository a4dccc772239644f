// `portico render`'s services on this machine: a coordinator on an ipc://
// socket in a private directory (mode 0700: no other user can reach it)
// with a private jobs.db, and N workers; and Ctrl-C, which ends a local run.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "common/util/child_process.h"
#include "coordinator/cli/commands.h"

namespace portico::cli {

class LocalServices {
 public:
  // Starts them; returns once the coordinator listens. Throws naming the log
  // when the coordinator exits or does not listen within 20 s.
  explicit LocalServices(const LocalRunOptions& local);
  ~LocalServices();
  LocalServices(const LocalServices&) = delete;
  LocalServices& operator=(const LocalServices&) = delete;

  const std::string& endpoint() const { return endpoint_; }
  const std::string& keys() const { return keys_; }
  // Why the services can no longer finish a job (the coordinator exited,
  // every worker exited), or nullopt while they can.
  std::optional<std::string> failure();
  // Stops them; keeps the directory (logs, jobs.db) and says where when
  // `keep`, removes it otherwise.
  void stop(bool keep);

 private:
  std::filesystem::path work_;
  std::string endpoint_, keys_, coordinatorLog_;
  std::optional<ChildProcess> coordinator_;
  std::vector<ChildProcess> workers_;
  bool stopped_ = false;
};

// SIGINT and SIGTERM set a flag instead of ending the process, so that a
// local run cancels its jobs and stops its services.
void catchInterrupts();
bool interrupted();

}  // namespace portico::cli
