#include "common/job/worker_tags.h"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

namespace portico {

namespace {
bool isAlphanumeric(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9'); }
}  // namespace

std::string tagNameProblem(std::string_view name) {
  if (name.empty()) return "a tag name is empty";
  if (name.size() > kMaxTagLength)
    return fmt::format("tag '{}...' is longer than {} characters", name.substr(0, 16), kMaxTagLength);
  if (!isAlphanumeric(name[0])) return fmt::format("tag '{}' does not start with a letter or digit", name);
  for (char c : name)
    if (!isAlphanumeric(c) && c != '-' && c != '_' && c != '.')
      return fmt::format("tag '{}' holds a character other than letters, digits, '-', '_' and '.'", name);
  return "";
}

std::vector<std::string> normalizedTags(std::vector<std::string> tags, std::string_view what) {
  for (const std::string& tag : tags)
    if (const std::string problem = tagNameProblem(tag); !problem.empty())
      throw std::invalid_argument(fmt::format("{}: {}", what, problem));
  std::sort(tags.begin(), tags.end());
  tags.erase(std::unique(tags.begin(), tags.end()), tags.end());
  if (tags.size() > kMaxTags)
    throw std::invalid_argument(fmt::format("{}: {} tags, at most {}", what, tags.size(), kMaxTags));
  return tags;
}

bool hasAllTags(const std::vector<std::string>& have, const std::vector<std::string>& need) {
  return std::includes(have.begin(), have.end(), need.begin(), need.end());
}

std::string joinTags(const std::vector<std::string>& tags) {
  std::string text;
  for (const std::string& tag : tags) text += (text.empty() ? "" : " ") + tag;
  return text;
}

std::vector<std::string> splitTags(std::string_view text) {
  std::vector<std::string> tags;
  while (!text.empty()) {
    const size_t space = text.find(' ');
    if (space != 0) tags.emplace_back(text.substr(0, space));
    if (space == std::string_view::npos) break;
    text.remove_prefix(space + 1);
  }
  return tags;
}

}  // namespace portico
