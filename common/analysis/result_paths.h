// The files an analysis writes beside its results: RESULTS.csv ->
// RESULTS.pts, RESULTS.rooms.csv, RESULTS.floor0.png, ...
#pragma once

#include <string>

namespace portico {

// `resultsPath` with its last extension replaced by `suffix` (appended
// when it has none): besideResults("out/R.csv", ".pts") == "out/R.pts".
inline std::string besideResults(const std::string& resultsPath, const std::string& suffix) {
  const size_t slash = resultsPath.find_last_of('/');
  const size_t dot = resultsPath.find_last_of('.');
  const bool hasExtension = dot != std::string::npos && (slash == std::string::npos ? dot > 0 : dot > slash + 1);
  return (hasExtension ? resultsPath.substr(0, dot) : resultsPath) + suffix;
}

}  // namespace portico
