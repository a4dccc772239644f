// The secret that opens `portico dashboard`'s page: 32 random bytes as 64
// hex digits, kept in the user's config folder ($XDG_CONFIG_HOME/portico/
// dashboard/token, else ~/.config/portico/dashboard/token; folder mode
// 0700, file 0600), so the same URL works after a restart, and checked as
// the key folders are (common/util/trusted_path.h): a token another user
// could have written (or read) is refused.
#pragma once

#include <string>
#include <string_view>

namespace portico::cli {

// The token file's path ("" when neither XDG_CONFIG_HOME nor HOME is set).
std::string defaultDashboardTokenPath();

// The token kept at `path`, written first when missing or when `renew`.
// Throws std::runtime_error naming the file and the problem.
std::string loadOrCreateDashboardToken(const std::string& path, bool renew);

// Whether `given` is `token`, in time independent of where they differ.
bool sameToken(std::string_view given, std::string_view token);

}  // namespace portico::cli
