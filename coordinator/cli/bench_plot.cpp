// The plotter behind `portico bench --plot`: an RGB canvas, lines (solid or
// dashed), markers, a 5x7 bitmap font, axes with decade or 1-2-5 ticks, and
// a PNG writer (zlib deflate, filter 0).
#include "coordinator/cli/bench_plot.h"

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>

namespace portico::cli {

namespace {

// ---------------------------------------------------------------------------
// Font: 5x7 glyphs, one string of 7 rows of 5 columns ('#' = ink) each;
// letters with descenders are drawn lower (Canvas::text).

struct Glyph {
  char character;
  const char* rows;  // 35 characters, row by row
};

constexpr Glyph kGlyphs[] = {
    {' ', "..................................."},
    {'0', ".###.#...##..###.#.###..##...#.###."},
    {'1', "..#...##....#....#....#....#...###."},
    {'2', ".###.#...#....#...#...#...#...#####"},
    {'3', "#####...#...#.....#.....##...#.###."},
    {'4', "...#...##..#.#.#..#.#####...#....#."},
    {'5', "######....####.....#....##...#.###."},
    {'6', "..##..#...#....####.#...##...#.###."},
    {'7', "#####....#...#...#...#....#....#..."},
    {'8', ".###.#...##...#.###.#...##...#.###."},
    {'9', ".###.#...##...#.####....#...#..##.."},
    {'A', ".###.#...##...#######...##...##...#"},
    {'B', "####.#...##...#####.#...##...#####."},
    {'C', ".###.#...##....#....#....#...#.###."},
    {'D', "###..#..#.#...##...##...##..#.###.."},
    {'E', "######....#....####.#....#....#####"},
    {'F', "######....#....####.#....#....#...."},
    {'G', ".###.#...##....#.####...##...#.####"},
    {'H', "#...##...##...#######...##...##...#"},
    {'I', ".###...#....#....#....#....#...###."},
    {'J', "..###...#....#....#....#.#..#..##.."},
    {'K', "#...##..#.#.#..##...#.#..#..#.#...#"},
    {'L', "#....#....#....#....#....#....#####"},
    {'M', "#...###.###.#.##.#.##...##...##...#"},
    {'N', "#...##...###..##.#.##..###...##...#"},
    {'O', ".###.#...##...##...##...##...#.###."},
    {'P', "####.#...##...#####.#....#....#...."},
    {'Q', ".###.#...##...##...##.#.##..#..##.#"},
    {'R', "####.#...##...#####.#.#..#..#.#...#"},
    {'S', ".#####....#.....###.....#....#####."},
    {'T', "#####..#....#....#....#....#....#.."},
    {'U', "#...##...##...##...##...##...#.###."},
    {'V', "#...##...##...##...##...#.#.#...#.."},
    {'W', "#...##...##...##.#.##.#.##.#.#.#.#."},
    {'X', "#...##...#.#.#...#...#.#.#...##...#"},
    {'Y', "#...##...#.#.#...#....#....#....#.."},
    {'Z', "#####....#...#...#...#...#....#####"},
    {'a', "...........###.....#.#####...#.####"},
    {'b', "#....#....#.##.##..##...##...#####."},
    {'c', "...........###.#....#....#...#.###."},
    {'d', "....#....#.##.##..###...##...#.####"},
    {'e', "...........###.#...#######.....###."},
    {'f', "..##..#..#.#...###...#....#....#..."},
    {'g', ".#####...##...#.####....#....#.###."},
    {'h', "#....#....#.##.##..##...##...##...#"},
    {'i', "..#........##....#....#....#...###."},
    {'j', "...#........##....#....#.#..#..##.."},
    {'k', "#....#....#..#.#.#..##...#.#..#..#."},
    {'l', ".##....#....#....#....#....#...###."},
    {'m', "..........##.#.#.#.##.#.##...##...#"},
    {'n', "..........#.##.##..##...##...##...#"},
    {'o', "...........###.#...##...##...#.###."},
    {'p', "####.#...##...#####.#....#....#...."},
    {'q', ".#####...##...#.####....#....#....#"},
    {'r', "..........#.##.##..##....#....#...."},
    {'s', "...........###.#.....###.....#####."},
    {'t', ".#....#...###...#....#....#..#..##."},
    {'u', "..........#...##...##...##..##.##.#"},
    {'v', "..........#...##...##...#.#.#...#.."},
    {'w', "..........#...##...##.#.##.#.#.#.#."},
    {'x', "..........#...#.#.#...#...#.#.#...#"},
    {'y', "#...##...##...#.####....##...#.###."},
    {'z', "..........#####...#...#...#...#####"},
    {'.', "..........................##...##.."},
    {',', ".....................##....#...#..."},
    {':', "......##...##........##...##......."},
    {'/', ".........#...#...#...#...#........."},
    {'-', "...............#####..............."},
    {'+', ".......#....#..#####..#....#......."},
    {'(', "...#...#...#....#....#.....#.....#."},
    {')', ".#.....#.....#....#....#...#...#..."},
    {'=', "..........#####.....#####.........."},
    {'_', "..............................#####"},
    {'%', "##...##..#...#...#...#...#..##...##"},
    {'*', ".......#..#.#.#.###.#.#.#..#......."},
    {'[', ".###..#....#....#....#....#....###."},
    {']', ".###....#....#....#....#....#..###."},
    {'^', "..#...#.#.#...#...................."},
    {'\'', "..#....#..........................."},
    {'?', ".###.#...#....#...#...#.........#.."},
};

constexpr bool everyGlyphIsFiveBySeven() {
  for (const Glyph& glyph : kGlyphs)
    if (std::char_traits<char>::length(glyph.rows) != 35) return false;
  return true;
}
static_assert(everyGlyphIsFiveBySeven(), "a glyph of the plot font is not 7 rows of 5");

// Returns the 35-character bitmap of c ('?' for characters without one).
const char* glyphRows(char c) {
  for (const Glyph& glyph : kGlyphs)
    if (glyph.character == c) return glyph.rows;
  return glyphRows('?');
}

// ---------------------------------------------------------------------------
// Canvas

using Color = std::array<uint8_t, 3>;
constexpr Color kBlack{0, 0, 0}, kGrey{120, 120, 120}, kLightGrey{225, 225, 225}, kWhite{255, 255, 255};
constexpr int kTextScale = 2;
constexpr int kCharAdvance = 6 * kTextScale;

class Canvas {
 public:
  Canvas(int width, int height) : width_(width), height_(height), pixels_(size_t(width) * height * 3, 255) {}
  int width() const { return width_; }
  int height() const { return height_; }
  const std::vector<uint8_t>& pixels() const { return pixels_; }

  void set(int x, int y, const Color& color) {
    if (x < 0 || y < 0 || x >= width_ || y >= height_) return;
    uint8_t* p = &pixels_[(size_t(y) * width_ + x) * 3];
    p[0] = color[0], p[1] = color[1], p[2] = color[2];
  }
  void fill(int x0, int y0, int x1, int y1, const Color& color) {
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) set(x, y, color);
  }
  // A line `thickness` pixels wide; dashed lines alternate 9 pixels on, 6 off.
  void line(double x0, double y0, double x1, double y1, const Color& color, int thickness, bool dashed) {
    const double steps = std::max({std::fabs(x1 - x0), std::fabs(y1 - y0), 1.0});
    for (int i = 0; i <= int(steps); ++i) {
      if (dashed && std::fmod(dashPhase_ + i, 15.0) >= 9.0) continue;
      const double t = i / steps;
      const int x = int(std::lround(x0 + t * (x1 - x0))), y = int(std::lround(y0 + t * (y1 - y0)));
      fill(x - thickness / 2, y - thickness / 2, x + (thickness - 1) / 2, y + (thickness - 1) / 2, color);
    }
    dashPhase_ = dashed ? std::fmod(dashPhase_ + steps, 15.0) : 0.0;
  }
  void resetDash() { dashPhase_ = 0; }
  // Text with its top-left corner at (x, y); vertical text reads bottom to top.
  void text(int x, int y, const std::string& s, const Color& color, bool vertical = false) {
    for (size_t i = 0; i < s.size(); ++i) {
      const char* rows = glyphRows(s[i]);
      // g, p, q and y are drawn two rows lower: their tails hang below the line.
      const int drop = std::char_traits<char>::find("gpqy", 4, s[i]) ? 2 : 0;
      for (int row = 0; row < 7; ++row)
        for (int column = 0; column < 5; ++column) {
          if (rows[row * 5 + column] != '#') continue;
          for (int dy = 0; dy < kTextScale; ++dy)
            for (int dx = 0; dx < kTextScale; ++dx) {
              const int gx = int(i) * kCharAdvance + column * kTextScale + dx,
                        gy = (row + drop) * kTextScale + dy;
              if (vertical)
                set(x + gy, y - gx, color);
              else
                set(x + gx, y + gy, color);
            }
        }
    }
  }

 private:
  int width_, height_;
  std::vector<uint8_t> pixels_;
  double dashPhase_ = 0;
};

int textWidth(const std::string& s) { return int(s.size()) * kCharAdvance - kTextScale; }

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
  canvas.text(originX + (kLeft + width - kRight) / 2 - textWidth(panel.title) / 2, 14, panel.title, kBlack);
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
      previous = true, lastX = x, lastY = y;
    }
    if (series.label.empty()) continue;
    canvas.resetDash();
    canvas.line(x1 + 12, legendY + 7, x1 + 40, legendY + 7, series.color, 3, series.dashed);
    for (const std::string& line : wrapLabel(series.label, (kRight - 50) / kCharAdvance)) {
      canvas.text(x1 + 46, legendY, line, kBlack);
      legendY += 20;
    }
    legendY += 2;
  }
}

// ---------------------------------------------------------------------------
// PNG

void appendBigEndian(std::vector<uint8_t>& out, uint32_t value) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(uint8_t(value >> shift));
}

void appendChunk(std::vector<uint8_t>& out, const char type[4], const std::vector<uint8_t>& data) {
  appendBigEndian(out, uint32_t(data.size()));
  const size_t start = out.size();
  out.insert(out.end(), type, type + 4);
  out.insert(out.end(), data.begin(), data.end());
  appendBigEndian(out, uint32_t(crc32(0, out.data() + start, uInt(out.size() - start))));
}

std::vector<uint8_t> encodePng(const Canvas& canvas) {
  const size_t stride = size_t(canvas.width()) * 3;
  std::vector<uint8_t> raw;
  raw.reserve((stride + 1) * canvas.height());
  for (int y = 0; y < canvas.height(); ++y) {
    raw.push_back(0);  // filter: none
    const uint8_t* row = canvas.pixels().data() + y * stride;
    raw.insert(raw.end(), row, row + stride);
  }
  uLongf compressedSize = compressBound(uLong(raw.size()));
  std::vector<uint8_t> compressed(compressedSize);
  if (compress2(compressed.data(), &compressedSize, raw.data(), uLong(raw.size()), 9) != Z_OK)
    throw std::runtime_error("zlib could not compress the plot");
  compressed.resize(compressedSize);

  std::vector<uint8_t> png{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  std::vector<uint8_t> header;
  appendBigEndian(header, uint32_t(canvas.width()));
  appendBigEndian(header, uint32_t(canvas.height()));
  header.insert(header.end(), {8, 2, 0, 0, 0});  // 8-bit RGB, deflate, no filter set, no interlace
  appendChunk(png, "IHDR", header);
  appendChunk(png, "IDAT", compressed);
  appendChunk(png, "IEND", {});
  return png;
}

}  // namespace

void writePlotPng(const std::string& path, const std::vector<PlotPanel>& panels, int panelWidth, int panelHeight) {
  Canvas canvas(std::max(1, panelWidth * int(panels.size())), panelHeight);
  canvas.fill(0, 0, canvas.width() - 1, canvas.height() - 1, kWhite);
  for (size_t i = 0; i < panels.size(); ++i) drawPanel(canvas, int(i) * panelWidth, panelWidth, panelHeight, panels[i]);
  const std::vector<uint8_t> png = encodePng(canvas);
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(png.data()), std::streamsize(png.size()));
  if (!out) throw std::runtime_error("cannot write the plot to " + path + " (check the directory exists and is writable)");
}

}  // namespace portico::cli
