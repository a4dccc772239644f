// Repeated warnings about one thing (a peer retrying with a wrong key every
// reconnect interval) are logged the first time, then at most once per
// interval with the number left out, so a log cannot be flooded.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <unordered_map>

namespace portico {

class LogThrottle {
 public:
  explicit LogThrottle(std::chrono::milliseconds interval = std::chrono::seconds(60)) : interval_(interval) {}

  // nullopt: stay quiet. Otherwise log now; the value is how many
  // occurrences of `key` were left out since its last line.
  std::optional<uint64_t> admit(const std::string& key) {
    const auto now = std::chrono::steady_clock::now();
    // Bounded memory whatever the number of distinct keys (random keys from a scanner).
    if (seen_.size() >= kMaxKeys && !seen_.count(key)) seen_.clear();
    auto [it, first] = seen_.try_emplace(key);
    Entry& entry = it->second;
    if (!first && now - entry.lastLogged < interval_) {
      ++entry.leftOut;
      return std::nullopt;
    }
    const uint64_t leftOut = entry.leftOut;
    entry = {now, 0};
    return leftOut;
  }

 private:
  static constexpr size_t kMaxKeys = 1024;
  struct Entry {
    std::chrono::steady_clock::time_point lastLogged;
    uint64_t leftOut = 0;
  };
  std::chrono::milliseconds interval_;
  std::unordered_map<std::string, Entry> seen_;
};

// The suffix of a throttled line: "" or "; N more since the last line".
inline std::string leftOutSuffix(uint64_t leftOut) {
  return leftOut ? "; " + std::to_string(leftOut) + " more since the last line" : std::string();
}

}  // namespace portico
