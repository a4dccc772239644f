// Bounded numeric options for CLI11. CLI11 reads "-1" into an unsigned
// option as 2^64-1 and "1e30" into nothing sensible; these validators look
// at the text first and refuse, in one line naming the bounds, any value
// that is not a number within them.
#pragma once

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <system_error>

#include "common/util/size_parse.h"

namespace portico::cli {

// A whole number in [min, max], written in decimal digits (a leading '-'
// only where min is negative).
inline CLI::Validator wholeNumber(int64_t min, uint64_t max) {
  return CLI::Validator(
      [min, max](std::string& text) -> std::string {
        const std::string expected = fmt::format("a whole number from {} to {}", min, max);
        const bool negative = !text.empty() && text[0] == '-';
        const char* first = text.data() + (negative ? 1 : 0);
        const char* last = text.data() + text.size();
        uint64_t magnitude = 0;
        const auto [end, error] = std::from_chars(first, last, magnitude);
        if (first == last || error != std::errc() || end != last)
          return fmt::format("'{}' is not {}", text, expected);
        const __int128 value = negative ? -__int128(magnitude) : __int128(magnitude);
        if (value < __int128(min) || value > __int128(max))
          return fmt::format("{} is out of range: expected {}", text, expected);
        return {};
      },
      fmt::format("INT in [{} - {}]", min, max));
}

// The whole text as a finite number; nullopt for anything else.
inline std::optional<double> finiteNumber(const std::string& text) {
  double value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || error != std::errc() || end != text.data() + text.size() || !std::isfinite(value))
    return std::nullopt;
  return value;
}

// A finite number in [min, max].
inline CLI::Validator realNumber(double min, double max) {
  return CLI::Validator(
      [min, max](std::string& text) -> std::string {
        const std::string expected = fmt::format("a number from {:g} to {:g}", min, max);
        const std::optional<double> value = finiteNumber(text);
        if (!value) return fmt::format("'{}' is not {}", text, expected);
        if (*value < min || *value > max) return fmt::format("{} is out of range: expected {}", text, expected);
        return {};
      },
      fmt::format("FLOAT in [{:g} - {:g}]", min, max));
}

// A finite number above 0 and at most max (0, negatives and NaN refused).
inline CLI::Validator positiveNumber(double max) {
  return CLI::Validator(
      [max](std::string& text) -> std::string {
        const std::string expected = fmt::format("a number above 0 and at most {:g}", max);
        const std::optional<double> value = finiteNumber(text);
        if (!value) return fmt::format("'{}' is not {}", text, expected);
        if (!(*value > 0) || *value > max) return fmt::format("{} is out of range: expected {}", text, expected);
        return {};
      },
      fmt::format("FLOAT in (0 - {:g}]", max));
}

// A byte size as parseByteSize reads it ("512MiB", "4GiB"), at most 1 PiB.
inline CLI::Validator byteSize() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        try {
          parseByteSize(text);
        } catch (const std::exception& e) {
          return e.what();
        }
        return {};
      },
      "SIZE");
}

// The least --memory a worker starts with: its own footprint at start (9
// MiB resident here), a lease's buffers (12 MiB) and room for cells (4 MiB),
// with a margin. Below it every worker would exit at start
// (worker_session.cpp cacheBudgetFor), after the command line passed.
constexpr uint64_t kLeastWorkerMemory = uint64_t(32) << 20;

// A worker's --memory: a byte size of at least kLeastWorkerMemory.
inline CLI::Validator workerMemory() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        try {
          if (parseByteSize(text) < kLeastWorkerMemory)
            return fmt::format("'{}' is too small: a worker needs at least {}MiB (its own code and a lease's "
                               "buffers, and room for cells)",
                               text, kLeastWorkerMemory >> 20);
        } catch (const std::exception& e) {
          return e.what();
        }
        return {};
      },
      "SIZE");
}

}  // namespace portico::cli
