// A tiny raster plotter for `portico bench`: line charts with log or linear
// axes, tick labels in a built-in 5x7 bitmap font, a legend, written as PNG
// with zlib. No OpenImageIO (it would add ~160 ms to every `portico` start)
// and no Python.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace portico::cli {

struct PlotSeries {
  std::string label;
  std::array<uint8_t, 3> color{0, 0, 0};
  bool dashed = false;
  std::vector<double> x, y;  // points with x > 0 (and y > 0 on a log axis) are drawn
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

}  // namespace portico::cli
