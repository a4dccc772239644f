// The plotter behind `portico bench --plot`: axes with decade or 1-2-5
// ticks, series as lines (solid or dashed) with markers, a legend; drawn on
// a Canvas (png_canvas.h).
#include "coordinator/cli/bench/bench_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "coordinator/cli/png_canvas.h"

namespace portico::cli {

namespace {

// ---------------------------------------------------------------------------
// Axes

struct Axis {
  bool log = false;
  double lo = 0, hi = 1;  // in log10 units when log
  std::vector<double> ticks;  // data values

  double position(double value) const {
    const double v = log ? std::log10(value) : value;
    return (v - lo) / (hi - lo);
  }
};

// The panel's title centred on centreX (the plot's middle) but kept within
// the panel; one too wide for the panel goes on two lines, broken after the
// last comma that lets the first line fit (else the last space).
void drawTitle(Canvas& canvas, int originX, int width, int centreX, const std::string& title) {
  const int room = width - 8;
  const auto centred = [&](const std::string& line, int y) {
    const int lowest = originX + 4, highest = std::max(lowest, originX + width - 4 - textWidth(line));
    canvas.text(std::clamp(centreX - textWidth(line) / 2, lowest, highest), y, line, kBlack);
  };
  if (textWidth(title) <= room) return centred(title, 14);
  const size_t fits = size_t(std::max(1, room / kCharAdvance));
  size_t cut = title.rfind(", ", fits - 1);
  cut = cut == std::string::npos ? title.rfind(' ', fits) : cut + 1;
  if (cut == std::string::npos || cut == 0) cut = fits;
  centred(title.substr(0, cut), 4);
  centred(title.substr(title[cut] == ' ' ? cut + 1 : cut), 8 + kTextHeight);
}

// "1k", "10k", "2.5M", "0.1", "40"...
std::string tickLabel(double value) {
  char buffer[32];
  const auto format = [&](double v, const char* suffix) {
    if (std::fabs(v - std::round(v)) < 1e-9 * std::max(1.0, std::fabs(v)))
      std::snprintf(buffer, sizeof buffer, "%.0f%s", v, suffix);
    else
      std::snprintf(buffer, sizeof buffer, "%.3g%s", v, suffix);
    return std::string(buffer);
  };
  const double magnitude = std::fabs(value);
  if (magnitude >= 1e9) return format(value / 1e9, "G");
  if (magnitude >= 1e6) return format(value / 1e6, "M");
  if (magnitude >= 1e3) return format(value / 1e3, "k");
  return format(value, "");
}

Axis makeAxis(bool log, double minimum, double maximum) {
  Axis axis;
  axis.log = log;
  if (!(minimum <= maximum)) minimum = maximum = log ? 1.0 : 0.0;
  if (log) {
    axis.lo = std::floor(std::log10(minimum));
    axis.hi = std::ceil(std::log10(maximum));
    if (axis.hi <= axis.lo) axis.hi = axis.lo + 1;
    for (double e = axis.lo; e <= axis.hi + 1e-9; e += 1) axis.ticks.push_back(std::pow(10.0, e));
    return axis;
  }
  // Linear, from 0 (or the minimum, if negative) to a 1-2-5 step above the maximum.
  axis.lo = std::min(0.0, minimum);
  const double span = std::max(maximum - axis.lo, 1e-12);
  const double raw = span / 5, power = std::pow(10.0, std::floor(std::log10(raw)));
  const double step = raw / power <= 1 ? power : raw / power <= 2 ? 2 * power : raw / power <= 5 ? 5 * power : 10 * power;
  axis.hi = axis.lo + step * std::ceil(span * 1.04 / step);
  for (double v = axis.lo; v <= axis.hi + 1e-9 * step; v += step) axis.ticks.push_back(v);
  return axis;
}

// Splits a legend label into lines of at most `width` characters, after a
// ':' or ',' where possible ("hgrid:res=16," / "max=64").
std::vector<std::string> wrapLabel(const std::string& label, int width) {
  std::vector<std::string> lines;
  std::string rest = label;
  while (int(rest.size()) > width && width > 0) {
    size_t cut = rest.find_last_of(":,", size_t(width - 1));
    cut = cut == std::string::npos ? size_t(width) : cut + 1;
    lines.push_back(rest.substr(0, cut));
    rest = rest.substr(cut);
  }
  lines.push_back(rest);
  return lines;
}

// A legend entry's label beside its swatch at (x, y), wrapped to `columns`
// characters; returns the y of the next entry.
int drawLegendLabel(Canvas& canvas, int x, int y, const std::string& label, int columns) {
  for (const std::string& line : wrapLabel(label, columns)) {
    canvas.text(x, y, line, kBlack);
    y += 20;
  }
  return y + 2;
}

// Panels side by side on one white canvas, written as a PNG (`what` names
// the kind of picture in errors).
template <typename Panel, typename DrawPanel>
void writePanelsPng(const std::string& path, const std::vector<Panel>& panels, int panelWidth, int panelHeight,
                    DrawPanel drawPanel, const char* what) {
  Canvas canvas(std::max(1, panelWidth * int(panels.size())), panelHeight);
  canvas.fill(0, 0, canvas.width() - 1, canvas.height() - 1, kWhite);
  for (size_t i = 0; i < panels.size(); ++i) drawPanel(canvas, int(i) * panelWidth, panelWidth, panelHeight, panels[i]);
  writePng(path, canvas, what);
}

// A ring round a point and its x value above it: the best of a sweep.
void drawMark(Canvas& canvas, int x, int y, const Color& color, const std::string& label) {
  constexpr int kRing = 8;
  canvas.line(x - kRing, y - kRing, x + kRing, y - kRing, color, 2, false);
  canvas.line(x + kRing, y - kRing, x + kRing, y + kRing, color, 2, false);
  canvas.line(x + kRing, y + kRing, x - kRing, y + kRing, color, 2, false);
  canvas.line(x - kRing, y + kRing, x - kRing, y - kRing, color, 2, false);
  canvas.text(x - textWidth(label) / 2, y - kRing - 4 - kTextHeight, label, color);
}

void drawPanel(Canvas& canvas, int originX, int width, int height, const PlotPanel& panel) {
  constexpr int kLeft = 90, kRight = 170, kTop = 44, kBottom = 64;
  const int x0 = originX + kLeft, x1 = originX + width - kRight, y0 = kTop, y1 = height - kBottom;

  double xMin = INFINITY, xMax = -INFINITY, yMin = INFINITY, yMax = -INFINITY;
  for (const PlotSeries& series : panel.series)
    for (size_t i = 0; i < series.x.size() && i < series.y.size(); ++i) {
      if (!(series.x[i] > 0) || !std::isfinite(series.y[i]) || (panel.logY && !(series.y[i] > 0))) continue;
      xMin = std::min(xMin, series.x[i]), xMax = std::max(xMax, series.x[i]);
      yMin = std::min(yMin, series.y[i]), yMax = std::max(yMax, series.y[i]);
    }
  const Axis xAxis = makeAxis(panel.logX, xMin, xMax);
  const Axis yAxis = makeAxis(panel.logY, yMin, yMax);
  const auto px = [&](double x) { return x0 + xAxis.position(x) * (x1 - x0); };
  const auto py = [&](double y) { return y1 - yAxis.position(y) * (y1 - y0); };

  // Grid, ticks and labels.
  for (double tick : xAxis.ticks) {
    const int x = int(std::lround(px(tick)));
    canvas.line(x, y0, x, y1, kLightGrey, 1, false);
    canvas.line(x, y1, x, y1 + 5, kBlack, 1, false);
    const std::string label = tickLabel(tick);
    canvas.text(x - textWidth(label) / 2, y1 + 10, label, kBlack);
  }
  for (double tick : yAxis.ticks) {
    const int y = int(std::lround(py(tick)));
    canvas.line(x0, y, x1, y, kLightGrey, 1, false);
    canvas.line(x0 - 5, y, x0, y, kBlack, 1, false);
    const std::string label = tickLabel(tick);
    canvas.text(x0 - 9 - textWidth(label), y - 7, label, kBlack);
  }
  canvas.line(x0, y0, x0, y1, kBlack, 1, false);
  canvas.line(x0, y1, x1, y1, kBlack, 1, false);
  canvas.line(x1, y0, x1, y1, kBlack, 1, false);
  canvas.line(x0, y0, x1, y0, kBlack, 1, false);
  drawTitle(canvas, originX, width, originX + (kLeft + width - kRight) / 2, panel.title);
  canvas.text((x0 + x1) / 2 - textWidth(panel.xLabel) / 2, y1 + 36, panel.xLabel, kGrey);
  canvas.text(originX + 12, (y0 + y1) / 2 + textWidth(panel.yLabel) / 2, panel.yLabel, kGrey, true);

  // Series, then the legend to the right of the plot.
  int legendY = y0 + 4;
  for (const PlotSeries& series : panel.series) {
    bool previous = false;
    double lastX = 0, lastY = 0;
    canvas.resetDash();
    for (size_t i = 0; i < series.x.size() && i < series.y.size(); ++i) {
      if (!(series.x[i] > 0) || !std::isfinite(series.y[i]) || (panel.logY && !(series.y[i] > 0))) {
        previous = false;
        continue;
      }
      const double x = px(series.x[i]), y = py(series.y[i]);
      if (previous) canvas.line(lastX, lastY, x, y, series.color, 2, series.dashed);
      canvas.fill(int(x) - 3, int(y) - 3, int(x) + 3, int(y) + 3, series.color);
      if (int(i) == series.marked) drawMark(canvas, int(x), int(y), series.color, tickLabel(series.x[i]));
      previous = true, lastX = x, lastY = y;
    }
    if (series.label.empty()) continue;
    canvas.resetDash();
    canvas.line(x1 + 12, legendY + 7, x1 + 40, legendY + 7, series.color, 3, series.dashed);
    legendY = drawLegendLabel(canvas, x1 + 46, legendY, series.label, (kRight - 50) / kCharAdvance);
  }
}

}  // namespace

void writePlotPng(const std::string& path, const std::vector<PlotPanel>& panels, int panelWidth, int panelHeight) {
  writePanelsPng(path, panels, panelWidth, panelHeight, drawPanel, "plot");
}

// ---------------------------------------------------------------------------
// Bar charts

namespace {

// The value axis: from 0 to a 1-2-5 tick above the tallest bar, with room
// left over it for the bar's text (written upright, or turned when the bar
// is too narrow for it).
Axis barAxis(const BarPanel& panel, int plotHeight) {
  double tallest = 0;
  for (const BarGroup& group : panel.groups)
    for (const Bar& bar : group.bars)
      if (std::isfinite(bar.value)) tallest = std::max(tallest, bar.value);
  const double headroom = double(plotHeight) / std::max(1, plotHeight - 90);
  return makeAxis(false, 0.0, std::max(tallest, 1e-9) * headroom);
}

void drawBarText(Canvas& canvas, int x0, int barWidth, int y, const Bar& bar) {
  const bool fits = std::max(textWidth(bar.above), textWidth(bar.aboveNote)) <= barWidth + 8;
  if (fits) {
    canvas.text(x0 + (barWidth - textWidth(bar.above)) / 2, y - 2 * kTextHeight - 10, bar.above, kBlack);
    canvas.text(x0 + (barWidth - textWidth(bar.aboveNote)) / 2, y - kTextHeight - 4, bar.aboveNote, kGrey);
    return;
  }
  // Too narrow: turned, reading upwards from just above the bar.
  const std::string text = bar.aboveNote.empty() ? bar.above : bar.above + " " + bar.aboveNote;
  canvas.text(x0 + (barWidth - kTextHeight) / 2, y - 4, text, kBlack, true);
}

void drawBarPanel(Canvas& canvas, int originX, int width, int height, const BarPanel& panel) {
  const int kLeft = 90, kRight = panel.legend.empty() ? 30 : 170, kTop = 44, kBottom = 70;
  const int x0 = originX + kLeft, x1 = originX + width - kRight, y0 = kTop, y1 = height - kBottom;
  const Axis axis = barAxis(panel, y1 - y0);
  const auto py = [&](double v) { return int(std::lround(y1 - axis.position(v) * (y1 - y0))); };
  for (double tick : axis.ticks) {
    const int y = py(tick);
    canvas.line(x0, y, x1, y, kLightGrey, 1, false);
    const std::string label = tickLabel(tick);
    canvas.text(x0 - 9 - textWidth(label), y - 7, label, kBlack);
  }
  canvas.line(x0, y0, x0, y1, kBlack, 1, false);
  canvas.line(x0, y1, x1, y1, kBlack, 1, false);
  drawTitle(canvas, originX, width, originX + (kLeft + width - kRight) / 2, panel.title);
  canvas.text(originX + 12, (y0 + y1) / 2 + textWidth(panel.yLabel) / 2, panel.yLabel, kGrey, true);

  const int slot = (x1 - x0) / std::max<int>(1, int(panel.groups.size()));
  for (size_t g = 0; g < panel.groups.size(); ++g) {
    const BarGroup& group = panel.groups[g];
    const int bars = std::max<int>(1, int(group.bars.size()));
    const int barWidth = std::max(2, std::min(140 / bars, slot * 4 / (5 * bars)));
    const int groupX = x0 + int(g) * slot + (slot - barWidth * bars) / 2;
    for (int b = 0; b < int(group.bars.size()); ++b) {
      const Bar& bar = group.bars[size_t(b)];
      const int bx = groupX + b * barWidth;
      const bool present = std::isfinite(bar.value) && bar.value >= 0;
      const int y = present ? py(bar.value) : y1;
      if (present) canvas.fill(bx + 1, y, bx + barWidth - 2, y1 - 1, bar.color);
      drawBarText(canvas, bx, barWidth, y, bar);
    }
    const int center = x0 + int(g) * slot + slot / 2;
    canvas.text(center - textWidth(group.label) / 2, y1 + 12, group.label, kBlack);
    canvas.text(center - textWidth(group.sublabel) / 2, y1 + 12 + kTextHeight + 8, group.sublabel, kGrey);
  }
  int legendY = y0 + 4;
  for (const auto& [label, color] : panel.legend) {
    canvas.fill(x1 + 12, legendY + 1, x1 + 36, legendY + 13, color);
    legendY = drawLegendLabel(canvas, x1 + 44, legendY, label, (kRight - 50) / kCharAdvance);
  }
}

}  // namespace

void writeBarPlotPng(const std::string& path, const std::vector<BarPanel>& panels, int panelWidth, int panelHeight) {
  writePanelsPng(path, panels, panelWidth, panelHeight, drawBarPanel, "bar chart");
}

}  // namespace portico::cli
