// Tables, CSV files and plot colours of `portico bench paper` (paper_output.h).
#include "coordinator/cli/bench/paper_output.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <stdexcept>

#include "common/util/csv_field.h"

namespace portico::cli::paper {

std::string formatSeconds(double seconds) { return std::isfinite(seconds) ? fmt::format("{:.2f}", seconds) : "n/a"; }
std::string formatRatio(double ratio) { return std::isfinite(ratio) ? fmt::format("{:.2f}", ratio) : "n/a"; }

void printTable(const std::string& title, const std::vector<std::string>& header,
                const std::vector<std::vector<std::string>>& rows, const std::string& footnote) {
  std::vector<size_t> widths(header.size());
  for (size_t c = 0; c < header.size(); ++c) widths[c] = header[c].size();
  for (const auto& row : rows)
    for (size_t c = 0; c < row.size() && c < widths.size(); ++c) widths[c] = std::max(widths[c], row[c].size());
  const auto line = [&](const std::vector<std::string>& cells) {
    std::string text;
    for (size_t c = 0; c < cells.size() && c < widths.size(); ++c)
      text += c == 0 ? fmt::format("{:<{}}", cells[c], widths[c]) : fmt::format("  {:>{}}", cells[c], widths[c]);
    return text + "\n";
  };
  std::cout << "\n== " << title << " ==\n" << line(header);
  for (const auto& row : rows) std::cout << line(row);
  if (!footnote.empty()) std::cout << footnote << "\n";
  std::cout.flush();
}

void Csv::write(const std::filesystem::path& path) const {
  std::ofstream out(path);
  out << text_;
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

std::string Csv::join(const std::vector<std::string>& cells) {
  std::string line;
  for (size_t i = 0; i < cells.size(); ++i) line += (i ? "," : "") + csvField(cells[i]);
  return line + "\n";
}

std::vector<std::string> concat(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

Rgb structureColor(const std::string& spec) {
  if (spec.rfind("grid", 0) == 0) return {31, 119, 180};
  if (spec.rfind("hgrid", 0) == 0) return {255, 127, 14};
  if (spec == "kd:median") return {44, 160, 44};
  if (spec == "kd:sah") return {214, 39, 40};
  if (spec == "kd:bbox") return {148, 103, 189};
  if (spec.rfind("kd", 0) == 0) return {140, 86, 75};
  if (spec == "embree") return {110, 110, 110};
  if (spec == "auto") return {227, 119, 194};
  if (spec.rfind("bvh", 0) == 0) return {188, 189, 34};
  return {23, 190, 207};
}

Bar timeBar(const std::string& spec, double seconds, const std::string& note) {
  Bar bar;
  bar.value = std::isfinite(seconds) ? seconds : std::numeric_limits<double>::quiet_NaN();
  bar.color = structureColor(spec);
  bar.above = std::isfinite(seconds) ? fmt::format("{:.1f}", seconds) : "n/a";
  bar.aboveNote = note;
  return bar;
}

}  // namespace portico::cli::paper
