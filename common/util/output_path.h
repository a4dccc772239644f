// An image output path checked before a job is accepted rather than after
// its render: a known image extension, not a directory, in a directory
// that exists and that the checking process may write. Nothing is created:
// the client checks as the user who asks, the coordinator as itself, and
// neither makes directories on another user's behalf.
#pragma once

#include <string>

namespace portico {

// Throws std::invalid_argument with a one-line message naming the path and
// the problem.
void checkOutputPath(const std::string& path);

}  // namespace portico
