// Starts a program as a child process with its output sent to a log file,
// and stops it (SIGTERM, then SIGKILL after a grace period).
#pragma once

#include <sys/types.h>

#include <chrono>
#include <string>
#include <vector>

namespace portico {

class ChildProcess {
 public:
  // Throws std::runtime_error naming the program if it cannot be started.
  ChildProcess(const std::vector<std::string>& argv, const std::string& logPath);
  ~ChildProcess();   // stops the child if still running
  ChildProcess(ChildProcess&& other) noexcept;
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  pid_t pid() const { return pid_; }
  bool running();                      // reaps it if it has exited
  int exitCode() const { return exitCode_; }
  void kill(int signal);
  // SIGTERM, wait up to grace, then SIGKILL. Returns the exit status.
  int stop(std::chrono::milliseconds grace = std::chrono::seconds(5));
  int wait();

 private:
  pid_t pid_ = -1;
  int exitCode_ = -1;
};

// The directory of the running executable (to find sibling programs).
std::string executableDirectory();
// `name` beside this executable, else on PATH; throws naming it if absent.
std::string findProgram(const std::string& name);

}  // namespace portico
