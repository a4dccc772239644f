// Progress of a job for people: a live bar on a terminal, plain lines in a
// log, and a one-screen description for `portico status`.
#pragma once

#include <nlohmann/json.hpp>

#include <string>

namespace portico::cli {

std::string describeStatus(const nlohmann::json& status);

// A job's state as status reports it: done, failed or cancelled (no more work).
inline bool jobEnded(const std::string& state) { return state == "done" || state == "failed" || state == "cancelled"; }

class ProgressDisplay {
 public:
  explicit ProgressDisplay(bool quiet);
  void update(const nlohmann::json& status);
  void finish(const nlohmann::json& status);

 private:
  bool quiet_;
  bool terminal_;
  int64_t lastLineMs_ = 0;
  std::string lastState_;   // and render pass: a new one gets a line
};

}  // namespace portico::cli
