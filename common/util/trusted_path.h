// Files only this user (or root) could have put in place, checked as ssh's
// StrictModes checks ~/.ssh: the CURVE key folders (common/net/curve_keys.h)
// and the dashboard's token (coordinator/cli/dashboard_token.h).
#pragma once

#include <filesystem>
#include <string_view>

namespace portico {

// Throws std::runtime_error naming the path unless it is owned by this user
// or root and writable by no one else (a read-only mount passes: no one can
// write there), and, for a directory, each folder above it is owned likewise
// and writable by others only when sticky (/tmp), where no one may move
// another's entry. `thing` names what it holds ("key": "key directory
// DIR: owned by uid ..."). A missing path passes: opening it says so.
void requireTrustedPath(const std::filesystem::path& path, bool directory, std::string_view thing);

}  // namespace portico
