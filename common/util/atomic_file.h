// Files that readers must never see half-written (statistics, calibrations,
// endpoint files): written beside the target, then renamed over it.
#pragma once

#include <string>

namespace portico {

// Writes `contents` to path + ".tmp", then renames it to `path` (creating
// the parent directory if needed). Throws std::runtime_error naming the path.
void writeFileAtomically(const std::string& path, const std::string& contents);

}  // namespace portico
