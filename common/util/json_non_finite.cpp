#include "common/util/json_non_finite.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <string_view>

namespace portico {

namespace {
// What a marker string starts with once parsed (written as \u0001 in JSON).
constexpr const char* kNonFiniteMarker = "\x01non-finite:";
}  // namespace

std::string markNonFiniteLiterals(const std::string& text) {
  static const char* const kLiterals[] = {"-Infinity", "Infinity", "NaN", "-inf", "inf", "-nan", "nan"};
  std::string out;
  out.reserve(text.size());
  bool inString = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (inString) {
      out += c;
      if (c == '\\' && i + 1 < text.size()) {
        out += text[++i];
      } else if (c == '"') {
        inString = false;
      }
      continue;
    }
    if (c == '"') {
      inString = true;
      out += c;
      continue;
    }
    bool replaced = false;
    for (const char* literal : kLiterals) {
      const std::string_view word(literal);
      if (text.compare(i, word.size(), word) != 0) continue;
      const size_t end = i + word.size();
      if (end < text.size() && (std::isalnum(static_cast<unsigned char>(text[end])) || text[end] == '_')) continue;
      out += fmt::format("\"\\u0001non-finite:{}\"", word);   // parses to kNonFiniteMarker + word
      i = end - 1;
      replaced = true;
      break;
    }
    if (!replaced) out += c;
  }
  return out;
}

std::optional<std::string> nonFiniteLiteral(const std::string& value) {
  const std::string_view marker(kNonFiniteMarker);
  if (value.rfind(marker, 0) != 0) return std::nullopt;
  return value.substr(marker.size());
}

std::string describeJsonError(const std::string& text, const nlohmann::json::exception& e) {
  constexpr int kNumberOverflow = 406;   // nlohmann's out_of_range.406: "number overflow parsing '1e400'"
  const std::string message = e.what();
  const size_t open = message.find('\''), close = message.rfind('\'');
  if (e.id != kNumberOverflow || open == std::string::npos || close <= open) return message;
  const std::string number = message.substr(open + 1, close - open - 1);
  const size_t at = text.find(number);
  if (at == std::string::npos) return fmt::format("the number {} is beyond a double's range", number);
  const auto line = 1 + std::count(text.begin(), text.begin() + std::ptrdiff_t(at), '\n');
  return fmt::format("line {}: the number {} is beyond a double's range", line, number);
}

}  // namespace portico
