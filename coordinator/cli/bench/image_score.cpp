#include "coordinator/cli/bench/image_score.h"

#include <fstream>
#include <iterator>
#include <regex>
#include <stdexcept>

#include "common/util/child_process.h"

namespace portico::cli {

ImageScore parseComparison(const std::string& text) {
  static const std::regex pattern(
      R"(([0-9.]+) % off.*block RMSE ([0-9.]+) %; relMSE ([0-9.e+-]+).*\(([0-9.]+) %\))");
  std::smatch match;
  if (!std::regex_search(text, match, pattern))
    throw std::runtime_error("portico-compare printed no comparison: " + text);
  ImageScore score;
  score.meanError = std::stod(match[1]) / 100;
  score.blockRmse = std::stod(match[2]) / 100;
  score.relativeMse = std::stod(match[3]);
  score.worstBlock = std::stod(match[4]) / 100;
  static const std::regex flip(R"(; FLIP ([0-9.]+))");
  if (std::regex_search(text, match, flip)) score.flip = std::stod(match[1]);
  return score;
}

ImageScore scoreImage(const std::string& compare, const std::filesystem::path& image,
                      const std::filesystem::path& reference, const std::filesystem::path& log) {
  ChildProcess comparison({compare, image.string(), reference.string()}, log.string());
  comparison.wait();
  std::ifstream in(log);
  return parseComparison(std::string(std::istreambuf_iterator<char>(in), {}));
}

}  // namespace portico::cli
