#include "common/analysis/pts_file.h"

#include "common/analysis/sensor_film.h"

#include <fmt/format.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <stdexcept>

namespace portico {

namespace {
bool isSeparator(char c) { return c == ' ' || c == '\t' || c == ',' || c == '\r'; }

// The line's numbers, or the problem with it.
std::string parseLine(const std::string& line, double (&values)[6]) {
  size_t at = 0, count = 0;
  while (true) {
    while (at < line.size() && isSeparator(line[at])) ++at;
    if (at == line.size()) break;
    size_t end = at;
    while (end < line.size() && !isSeparator(line[end])) ++end;
    const std::string word = line.substr(at, end - at);
    if (count == 6) return fmt::format("more than 6 numbers (expected x y z dx dy dz); '{}' is the 7th", word);
    double value = 0;
    const auto [next, error] = std::from_chars(word.data(), word.data() + word.size(), value);
    if (error != std::errc() || next != word.data() + word.size())
      return fmt::format("'{}' is not a number (expected x y z dx dy dz)", word);
    if (!std::isfinite(value)) return fmt::format("'{}' is not a finite number", word);
    values[count++] = value;
    at = end;
  }
  if (count < 6) return fmt::format("{} numbers, expected 6 (x y z dx dy dz)", count);
  const double length = std::sqrt(values[3] * values[3] + values[4] * values[4] + values[5] * values[5]);
  if (!(length > 1e-12) || !std::isfinite(length)) return "the direction dx dy dz is zero";
  for (const double v : values)
    if (std::abs(v) > 1e9) return fmt::format("{} is beyond 1e9 metres", v);
  return "";
}
}  // namespace

std::vector<Sensor> readPtsFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument(fmt::format("{}: cannot read: {}", path, std::strerror(errno)));
  std::vector<Sensor> sensors;
  std::string line;
  for (uint32_t number = 1; std::getline(in, line); ++number) {
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    double v[6];
    if (const std::string problem = parseLine(line, v); !problem.empty())
      throw std::invalid_argument(fmt::format("{}:{}: {}", path, number, problem));
    Sensor sensor;
    sensor.position = Vec3(float(v[0]), float(v[1]), float(v[2]));
    const double length = std::sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5]);
    sensor.direction = Vec3(float(v[3] / length), float(v[4] / length), float(v[5] / length));
    sensor.sourceLine = number;
    sensors.push_back(std::move(sensor));
    if (sensors.size() > kMaxSensors)
      throw std::invalid_argument(fmt::format("{}:{}: more than {} sensors", path, number, kMaxSensors));
  }
  if (in.bad()) throw std::invalid_argument(fmt::format("{}: read error: {}", path, std::strerror(errno)));
  if (sensors.empty()) throw std::invalid_argument(fmt::format("{}: no sensor in it (lines of x y z dx dy dz)", path));
  return sensors;
}

}  // namespace portico
