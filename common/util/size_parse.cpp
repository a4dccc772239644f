#include "common/util/size_parse.h"

#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <stdexcept>

namespace portico {

uint64_t parseByteSize(const std::string& text) {
  size_t end = 0;
  double value = 0;
  try {
    value = std::stod(text, &end);
  } catch (...) {
    throw std::invalid_argument(fmt::format("size '{}' is not a number with an optional unit", text));
  }
  std::string unit = text.substr(end);
  for (char& c : unit) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  double scale = 1;
  if (unit.empty() || unit == "b") scale = 1;
  else if (unit == "k" || unit == "kb" || unit == "kib") scale = 1024.0;
  else if (unit == "m" || unit == "mb" || unit == "mib") scale = 1024.0 * 1024;
  else if (unit == "g" || unit == "gb" || unit == "gib") scale = 1024.0 * 1024 * 1024;
  else if (unit == "t" || unit == "tb" || unit == "tib") scale = 1024.0 * 1024 * 1024 * 1024;
  else throw std::invalid_argument(fmt::format("size '{}': unknown unit '{}' (use KiB, MiB, GiB)", text, unit));
  if (!(value > 0) || !std::isfinite(value)) throw std::invalid_argument(fmt::format("size '{}' must be positive", text));
  // Beyond 2^64 the conversion is undefined (1e30 came out as 0 bytes).
  if (value * scale > double(kMaxByteSize))
    throw std::invalid_argument(fmt::format("size '{}' is too large: at most 1 PiB", text));
  return static_cast<uint64_t>(value * scale);
}

}  // namespace portico
