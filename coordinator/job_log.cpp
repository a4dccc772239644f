#include "coordinator/job_log.h"

#include <fmt/chrono.h>

#include <regex>

namespace portico {

std::vector<std::string> JobLog::lines(uint64_t job) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = lines_.find(job);
  if (it == lines_.end()) return {};
  return {it->second.begin(), it->second.end()};
}

void JobLog::sink_it_(const spdlog::details::log_msg& message) {
  // Lines name their job as "job N" (and a lease's as "(job N cell C ...");
  // a line naming two jobs (a reused photon pass) belongs to both.
  static const std::regex kJobWord(R"(\bjob (\d{1,19})\b)");
  const std::string text(message.payload.data(), message.payload.size());
  std::vector<uint64_t> jobs;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), kJobWord); it != std::sregex_iterator(); ++it) {
    const uint64_t job = std::stoull((*it)[1].str());
    if (std::find(jobs.begin(), jobs.end(), job) == jobs.end()) jobs.push_back(job);
  }
  if (jobs.empty()) return;
  const std::string line = fmt::format("{:%H:%M:%S} [{}] {}", fmt::localtime(std::chrono::system_clock::to_time_t(message.time)),
                                       spdlog::level::to_string_view(message.level), text);
  for (const uint64_t job : jobs) {
    auto& kept = lines_[job];
    kept.push_back(line);
    if (kept.size() > kLinesPerJob) kept.pop_front();
  }
  // The oldest jobs go first: ids grow with submission.
  while (lines_.size() > kJobs) lines_.erase(lines_.begin());
}

}  // namespace portico
