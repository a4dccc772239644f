// JSON has no NaN or infinity, but Python's json module (and others) write
// NaN, Infinity and -Infinity bare. Before parsing, each such token outside
// a string becomes a marker string, so that a reader can name the field
// holding it instead of a byte offset (building.json, views files).
#pragma once

#include <nlohmann/json.hpp>

#include <optional>
#include <string>

namespace portico {

std::string markNonFiniteLiterals(const std::string& text);

// The literal (e.g. "NaN") a parsed marker string stands for; nothing when
// `value` is an ordinary string.
std::optional<std::string> nonFiniteLiteral(const std::string& value);

// Why `text` did not parse, in one line with where: nlohmann's own message
// for a syntax error (it gives line and column), and for a number beyond a
// double's range (1e400), which it reports with no position, the line the
// number is on.
std::string describeJsonError(const std::string& text, const nlohmann::json::exception& e);

}  // namespace portico
