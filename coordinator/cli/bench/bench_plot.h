// A tiny raster plotter for `portico bench`: line charts with log or linear
// axes, tick labels in a built-in 5x7 bitmap font, a legend, written as PNG
// with zlib. No OpenImageIO (it would add ~160 ms to every `portico` start)
// and no Python.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace portico::cli {

struct PlotSeries {
  std::string label;
  std::array<uint8_t, 3> color{0, 0, 0};
  bool dashed = false;
  std::vector<double> x, y;  // points with x > 0 (and y > 0 on a log axis) are drawn
  int marked = -1;           // index of a point ringed and labelled with its x (e.g. the best), -1: none
};

struct PlotPanel {
  std::string title;
  std::string xLabel, yLabel;
  bool logX = true, logY = false;
  std::vector<PlotSeries> series;
};

// Draws the panels side by side (each width x height pixels) and writes a
// PNG. Throws std::runtime_error naming the file if it cannot be written.
void writePlotPng(const std::string& path, const std::vector<PlotPanel>& panels, int panelWidth = 640,
                  int panelHeight = 480);

// Bar charts: groups of bars along x (a building, a mode), one bar per
// series in each group, on a linear y axis from 0.
struct Bar {
  double value = 0;           // not finite or < 0: no bar (a missing measurement), `above` still written
  std::array<uint8_t, 3> color{31, 119, 180};
  std::string above;          // text above the bar (its value, "n/a", ...)
  std::string aboveNote;      // a second, grey line above that one (a ratio, ...)
};

struct BarGroup {
  std::string label;          // under the group
  std::string sublabel;       // a grey line under the label
  std::vector<Bar> bars;
};

struct BarPanel {
  std::string title;
  std::string yLabel;
  std::vector<BarGroup> groups;
  std::vector<std::pair<std::string, std::array<uint8_t, 3>>> legend;  // empty: none
};

// Draws the panels side by side (each width x height pixels) and writes a
// PNG. Throws std::runtime_error naming the file if it cannot be written.
void writeBarPlotPng(const std::string& path, const std::vector<BarPanel>& panels, int panelWidth = 760,
                     int panelHeight = 480);

}  // namespace portico::cli
