// JSON has no NaN or infinity, but Python's json module (and others) write
// NaN, Infinity and -Infinity bare. Before parsing, each such token outside
// a string becomes a marker string, so that a reader can name the field
// holding it instead of a byte offset (building.json, views files).
#pragma once

#include <optional>
#include <string>

namespace portico {

std::string markNonFiniteLiterals(const std::string& text);

// The literal (e.g. "NaN") a parsed marker string stands for; nothing when
// `value` is an ordinary string.
std::optional<std::string> nonFiniteLiteral(const std::string& value);

}  // namespace portico
