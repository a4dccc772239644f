// Small IES LM-63 files written by the tests: a candela function sampled on
// a grid of angles, so each file's total lumens has a closed form.
#pragma once

#include <fmt/format.h>

#include <functional>
#include <string>
#include <vector>

namespace portico::ies_test {

// Angles from `first` to `last` in `step` degrees.
inline std::vector<double> angles(double first, double last, double step) {
  std::vector<double> out;
  for (double a = first; a <= last + 1e-9; a += step) out.push_back(a);
  return out;
}

// An LM-63-2002 file (or `header`) of `candela(gamma, c)` on the grid, its
// luminous opening `opening` (width length height, metres).
inline std::string iesText(const std::vector<double>& vertical, const std::vector<double>& horizontal,
                           const std::function<double(double, double)>& candela, double multiplier = 1.0,
                           double ballastFactor = 1.0, const std::string& header = "IESNA:LM-63-2002",
                           double thirdField = 1.0, const std::string& opening = "0.1 0.1 0") {
  std::string text = header + "\n[TEST] portico unit test\n[LUMINAIRE] analytic distribution\nTILT=NONE\n";
  text += fmt::format("1 -1 {} {} {} 1 2 {}\n{} {} 20\n", multiplier, vertical.size(), horizontal.size(), opening,
                      ballastFactor, thirdField);
  for (double v : vertical) text += fmt::format("{} ", v);
  text += "\n";
  for (double h : horizontal) text += fmt::format("{} ", h);
  text += "\n";
  for (double h : horizontal) {
    for (double v : vertical) text += fmt::format("{:.9g} ", candela(v, h));
    text += "\n";
  }
  return text;
}

}  // namespace portico::ies_test
