// Reading `portico analyze`'s results in the tests: its CSV as rows of
// fields (no field of these tests holds a comma), and each measured row's
// numbers by column name.
#pragma once

#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace portico::harness {

inline std::vector<std::vector<std::string>> csvRows(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> cells;
    std::istringstream fields(line);
    for (std::string cell; std::getline(fields, cell, ',');) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.push_back("");
    rows.push_back(cells);
  }
  return rows;
}

// Row i (from 0, after the header) as column name -> number; empty fields left out.
inline std::vector<std::map<std::string, double>> csvNumbers(const std::string& text) {
  const auto rows = csvRows(text);
  std::vector<std::map<std::string, double>> out;
  for (size_t r = 1; r < rows.size(); ++r) {
    std::map<std::string, double> row;
    for (size_t c = 0; c < rows[r].size() && c < rows[0].size(); ++c)
      if (!rows[r][c].empty() && c != 1) row[rows[0][c]] = std::stod(rows[r][c]);
    out.push_back(row);
  }
  return out;
}

}  // namespace portico::harness
