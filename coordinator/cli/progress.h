// Progress of a job for people: a live bar on a terminal, plain lines in a
// log, and a one-screen description for `portico status`.
#pragma once

#include <nlohmann/json.hpp>

#include <string>

namespace portico::cli {

std::string describeStatus(const nlohmann::json& status);

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
