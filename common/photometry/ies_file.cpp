// LM-63 layout, after the header line and keyword lines: TILT=..., then
// numbers separated by blanks, commas or line ends: lamp count, lumens per
// lamp (-1: absolute photometry), candela multiplier, vertical and
// horizontal angle counts, photometric type (1 C, 2 B, 3 A), units (1 feet,
// 2 metres), width, length, height; ballast factor, ballast-lamp factor
// (LM-63-2002: future use; -2019: file generation type), input watts; the
// vertical angles, the horizontal angles, and the candela values, one
// vertical row per horizontal angle.
#include "common/photometry/ies_file.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace portico {

namespace {

constexpr size_t kMaxAngles = 100000;
constexpr size_t kMaxCandelaValues = 4000000;

struct Token {
  std::string_view text;
  size_t line;   // 1-based
};

std::string_view trimmed(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

class NumberReader {
 public:
  NumberReader(const std::string& name, std::vector<Token> tokens, size_t lastLine)
      : name_(name), tokens_(std::move(tokens)), lastLine_(lastLine) {}

  [[noreturn]] void fail(size_t line, const std::string& problem) const {
    throw std::runtime_error(fmt::format("{}: line {}: {}", name_, line, problem));
  }
  size_t line() const { return next_ < tokens_.size() ? tokens_[next_].line : lastLine_; }
  size_t previousLine() const { return next_ > 0 ? tokens_[next_ - 1].line : lastLine_; }

  double number(const std::string& what) {
    if (next_ >= tokens_.size()) fail(lastLine_, fmt::format("the file ends before {} (truncated?)", what));
    const Token& token = tokens_[next_++];
    double value = 0;
    const char* begin = token.text.data() + (token.text.front() == '+' ? 1 : 0);   // from_chars takes no '+'
    const char* end = token.text.data() + token.text.size();
    const auto [stop, error] = std::from_chars(begin, end, value);
    if (error != std::errc() || stop != end || !std::isfinite(value))
      fail(token.line, fmt::format("'{}' is not a number ({})", token.text, what));
    return value;
  }
  size_t count(const std::string& what, size_t minimum, size_t maximum) {
    const double value = number(what);
    if (value != std::floor(value) || value < double(minimum) || value > double(maximum))
      fail(previousLine(), fmt::format("{} = {} must be a whole number from {} to {}", what, value, minimum, maximum));
    return static_cast<size_t>(value);
  }
  double positive(const std::string& what) {
    const double value = number(what);
    if (!(value > 0)) fail(previousLine(), fmt::format("{} = {} must be above 0", what, value));
    return value;
  }
  void requireEnd() const {
    if (next_ < tokens_.size())
      fail(tokens_[next_].line, fmt::format("'{}' follows the last candela value (more values than the angle counts say)",
                                            tokens_[next_].text));
  }

 private:
  const std::string& name_;
  std::vector<Token> tokens_;
  size_t next_ = 0;
  size_t lastLine_;
};

// Angles that must increase strictly, read from `reader`.
std::vector<double> readAngles(NumberReader& reader, size_t count, const char* kind) {
  std::vector<double> angles(count);
  for (size_t i = 0; i < count; ++i) {
    angles[i] = reader.number(fmt::format("{} angle {} of {}", kind, i + 1, count));
    if (i > 0 && !(angles[i] > angles[i - 1]))
      reader.fail(reader.previousLine(), fmt::format("{} angle {} ({}) does not increase from the one before ({})", kind,
                                                     i + 1, angles[i], angles[i - 1]));
  }
  return angles;
}

}  // namespace

IesPhotometry parseIes(std::string_view text, const std::string& name) {
  std::vector<std::string_view> lines;
  for (size_t start = 0; start <= text.size();) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(start, end - start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    lines.push_back(line);
    start = end + 1;
  }
  IesPhotometry ies;
  const std::string_view first = trimmed(lines.front());
  size_t at = 1;   // the line after the header
  if (first.rfind("IESNA:LM-63-2002", 0) == 0)
    ies.standard = "LM-63-2002";
  else if (first.rfind("IESNA:LM-63-1995", 0) == 0)
    ies.standard = "LM-63-1995";
  else if (first.rfind("IES:LM-63-2019", 0) == 0)
    ies.standard = "LM-63-2019";
  else if (first.rfind("IESNA91", 0) == 0)
    ies.standard = "LM-63-1991";
  else
    ies.standard = "LM-63-1986", at = 0;   // no header line: labels up to TILT=
  const bool olderThan2002 = ies.standard == "LM-63-1995" || ies.standard == "LM-63-1991" || ies.standard == "LM-63-1986";
  while (at < lines.size() && trimmed(lines[at]).rfind("TILT=", 0) != 0) ++at;
  if (at >= lines.size())
    throw std::runtime_error(fmt::format("{}: line {}: no TILT= line: not an IES LM-63 photometric file", name,
                                         lines.size()));
  const std::string_view tilt = trimmed(trimmed(lines[at]).substr(5));
  if (tilt == "INCLUDE")
    throw std::runtime_error(fmt::format(
        "{}: line {}: TILT=INCLUDE (lamp output by tilt angle) is not supported; only TILT=NONE", name, at + 1));
  if (tilt != "NONE")
    throw std::runtime_error(fmt::format("{}: line {}: TILT={} (a tilt file) is not supported; only TILT=NONE", name,
                                         at + 1, tilt));
  std::vector<Token> tokens;
  for (size_t l = at + 1; l < lines.size(); ++l) {
    const std::string_view line = lines[l];
    size_t i = 0;
    while (i < line.size()) {
      while (i < line.size() && (std::isspace(static_cast<unsigned char>(line[i])) || line[i] == ',')) ++i;
      const size_t start = i;
      while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i])) && line[i] != ',') ++i;
      if (i > start) tokens.push_back({line.substr(start, i - start), l + 1});
    }
  }
  size_t lastLine = lines.size();
  while (lastLine > at + 1 && trimmed(lines[lastLine - 1]).empty()) --lastLine;
  NumberReader reader(name, std::move(tokens), lastLine);

  ies.lampCount = static_cast<int>(reader.count("the number of lamps", 1, 1000));
  ies.lumensPerLamp = reader.number("the lumens per lamp");
  if (!(ies.lumensPerLamp > 0 || ies.lumensPerLamp == -1))
    reader.fail(reader.previousLine(),
                fmt::format("lumens per lamp = {} must be above 0, or -1 (absolute photometry)", ies.lumensPerLamp));
  ies.candelaMultiplier = reader.positive("the candela multiplier");
  const size_t verticalCount = reader.count("the number of vertical angles", 2, kMaxAngles);
  const size_t horizontalCount = reader.count("the number of horizontal angles", 1, kMaxAngles);
  if (verticalCount * horizontalCount > kMaxCandelaValues)
    reader.fail(reader.previousLine(), fmt::format("{} x {} candela values are more than the {} read",
                                                   verticalCount, horizontalCount, kMaxCandelaValues));
  const size_t type = reader.count("the photometric type", 1, 3);
  if (type != 1)
    reader.fail(reader.previousLine(), fmt::format("photometric type {} ({}) is not supported; only type C (1)", type,
                                                   type == 2 ? "B" : "A"));
  const size_t units = reader.count("the units type (1 feet, 2 metres)", 1, 2);
  const double metres = units == 1 ? 0.3048 : 1.0;
  ies.width = reader.number("the width") * metres;
  ies.length = reader.number("the length") * metres;
  ies.height = reader.number("the height") * metres;
  try {
    ies.opening = LuminousOpening::fromLm63(ies.width, ies.length, ies.height);
  } catch (const std::invalid_argument& e) {
    reader.fail(reader.previousLine(), e.what());
  }
  ies.ballastFactor = reader.positive("the ballast factor");
  const double thirdField = reader.number(olderThan2002 ? "the ballast-lamp photometric factor" : "the future-use field");
  if (olderThan2002) {
    if (!(thirdField > 0))
      reader.fail(reader.previousLine(), fmt::format("the ballast-lamp photometric factor = {} must be above 0", thirdField));
    ies.ballastLampFactor = thirdField;
  }
  reader.number("the input watts");

  CandelaGrid& grid = ies.grid;
  const size_t verticalLine = reader.line();
  grid.vertical = readAngles(reader, verticalCount, "vertical");
  if (!(grid.vertical.front() == 0.0 || grid.vertical.front() == 90.0) ||
      !(grid.vertical.back() == 90.0 || grid.vertical.back() == 180.0))
    reader.fail(verticalLine, fmt::format("the vertical angles run {}-{}; type C runs from 0 or 90 to 90 or 180 degrees",
                                          grid.vertical.front(), grid.vertical.back()));
  const size_t horizontalLine = reader.line();
  grid.horizontal = readAngles(reader, horizontalCount, "horizontal");
  grid.candela.resize(verticalCount * horizontalCount);
  if (const std::string problem = grid.problem(); !problem.empty() && problem.find("horizontal") != std::string::npos)
    reader.fail(horizontalLine, problem);
  const double scale =
      ies.candelaMultiplier * ies.ballastFactor * (olderThan2002 ? ies.ballastLampFactor : 1.0);
  for (size_t h = 0; h < horizontalCount; ++h)
    for (size_t v = 0; v < verticalCount; ++v) {
      const double value = reader.number(fmt::format("candela value {} of {} (horizontal angle {}, vertical angle {})",
                                                     h * verticalCount + v + 1, grid.candela.size(),
                                                     grid.horizontal[h], grid.vertical[v]));
      if (value < 0)
        reader.fail(reader.previousLine(),
                    fmt::format("candela value {} (horizontal angle {}, vertical angle {}) is negative",
                                value, grid.horizontal[h], grid.vertical[v]));
      grid.candela[h * verticalCount + v] = value * scale;
    }
  reader.requireEnd();
  if (const std::string problem = grid.problem(); !problem.empty()) reader.fail(verticalLine, problem);
  return ies;
}

IesPhotometry readIesFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(fmt::format("{}: cannot be read", path));
  std::stringstream text;
  text << in.rdbuf();
  if (in.bad()) throw std::runtime_error(fmt::format("{}: cannot be read", path));
  return parseIes(text.str(), path);
}

}  // namespace portico
