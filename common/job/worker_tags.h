// Worker pools: a worker's tags (`portico-worker --tag NAME`) and the tags
// a job requires (`portico submit --require NAME`). A job's leases go only
// to workers having every tag it requires: big-memory machines can be kept
// for the big jobs, and no tag changes what a job computes. Names are
// checked alike by the worker, the client and the coordinator (a hand-made
// message gets no further than the command line).
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace portico {

// Longest tag name, and most tags a worker or a job may name.
constexpr size_t kMaxTagLength = 64;
constexpr size_t kMaxTags = 32;

// Why `name` is no tag name ("" when it is one): 1 to kMaxTagLength ASCII
// letters, digits, '-', '_' or '.', starting with a letter or digit (so a
// tag never reads as an option and needs no quoting in a status line).
std::string tagNameProblem(std::string_view name);

// `tags` sorted and without repeats; throws std::invalid_argument in one
// line naming the first bad tag (`what`: "--tag", "--require", ...).
std::vector<std::string> normalizedTags(std::vector<std::string> tags, std::string_view what);

// Whether `have` (sorted) holds every tag of `need` (sorted).
bool hasAllTags(const std::vector<std::string>& have, const std::vector<std::string>& need);

// As jobs.db keeps them: names separated by single spaces, and back.
std::string joinTags(const std::vector<std::string>& tags);
std::vector<std::string> splitTags(std::string_view text);

}  // namespace portico
