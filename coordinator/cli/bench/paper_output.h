// What the experiments of `portico bench paper` print and write: tables on
// stdout, CSV files, and the colours and bars of their plots.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "coordinator/cli/bench/bench_plot.h"

namespace portico::cli::paper {

using Rgb = std::array<uint8_t, 3>;

// Two decimals, or "n/a" for a measurement that did not run (NaN).
std::string formatSeconds(double seconds);
std::string formatRatio(double ratio);

// A titled table on stdout: the first column left-aligned, the others right.
void printTable(const std::string& title, const std::vector<std::string>& header,
                const std::vector<std::vector<std::string>>& rows, const std::string& footnote = "");

// A CSV file's text, written at once (fields quoted where they need it).
class Csv {
 public:
  explicit Csv(const std::vector<std::string>& header) : text_(join(header)) {}
  void row(const std::vector<std::string>& cells) { text_ += join(cells); }
  // Throws std::runtime_error naming the file when it cannot be written.
  void write(const std::filesystem::path& path) const;

 private:
  static std::string join(const std::vector<std::string>& cells);
  std::string text_;
};

std::vector<std::string> concat(std::vector<std::string> a, const std::vector<std::string>& b);

// Colours of the structures, the same in every plot.
Rgb structureColor(const std::string& spec);
inline constexpr Rgb kBestGridColor{158, 202, 225};   // grid at its best resolution, beside plain `grid`
inline constexpr Rgb kSeriesColors[] = {{31, 119, 180}, {255, 127, 14}, {44, 160, 44},  {214, 39, 40},
                                 {148, 103, 189}, {140, 86, 75}, {227, 119, 194}, {23, 190, 207}};

// A bar of photon-pass seconds in the structure's colour ("n/a" when it did not run).
Bar timeBar(const std::string& spec, double seconds, const std::string& note = "");

}  // namespace portico::cli::paper
