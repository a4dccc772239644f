#include "common/util/json_non_finite.h"

#include <fmt/format.h>

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

}  // namespace portico
