// An image scored against a reference by `portico-compare`, as the benches
// that measure error read it (bench quality, bench lights).
#pragma once

#include <filesystem>
#include <optional>
#include <string>

namespace portico::cli {

struct ImageScore {
  double meanError = 0, worstBlock = 0, blockRmse = 0, relativeMse = 0;   // fractions (0.01: 1 %)
  std::optional<double> flip;   // unset where flip-evaluator is not installed
};

// portico-compare's line: "... X % off; ... block RMSE Y %; relMSE R; worst
// block at (..): a vs b (Z %); FLIP F" (or "FLIP skipped: why"). Throws
// when `text` holds no such line.
ImageScore parseComparison(const std::string& text);

// Runs `compare` (portico-compare) on `image` against `reference`, its
// output in `log`. portico-compare exits 1 when a block is over the
// reference test's limit: a measured image may well be; its line is what
// counts here.
ImageScore scoreImage(const std::string& compare, const std::filesystem::path& image,
                      const std::filesystem::path& reference, const std::filesystem::path& log);

}  // namespace portico::cli
