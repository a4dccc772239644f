// The canvas behind `portico bench --plot` and `portico scene plan`: pixels,
// lines, a 5x7 bitmap font; libpng writes it (common/image/png_file.h).
#include "coordinator/cli/png_canvas.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/image/png_file.h"

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


}  // namespace

// ---------------------------------------------------------------------------
// Canvas

int textWidth(const std::string& s) { return int(s.size()) * kCharAdvance - kTextScale; }

void Canvas::fill(int x0, int y0, int x1, int y1, const Color& color) {
  // Clipped first: a plan's cell may reach far outside a panel.
  x0 = std::max(x0, 0), y0 = std::max(y0, 0), x1 = std::min(x1, width_ - 1), y1 = std::min(y1, height_ - 1);
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) set(x, y, color);
}

void Canvas::line(double x0, double y0, double x1, double y1, const Color& color, int thickness, bool dashed) {
  const double steps = std::max({std::fabs(x1 - x0), std::fabs(y1 - y0), 1.0});
  for (int i = 0; i <= int(steps); ++i) {
    if (dashed && std::fmod(dashPhase_ + i, 15.0) >= 9.0) continue;
    const double t = i / steps;
    const int x = int(std::lround(x0 + t * (x1 - x0))), y = int(std::lround(y0 + t * (y1 - y0)));
    fill(x - thickness / 2, y - thickness / 2, x + (thickness - 1) / 2, y + (thickness - 1) / 2, color);
  }
  dashPhase_ = dashed ? std::fmod(dashPhase_ + steps, 15.0) : 0.0;
}

void Canvas::text(int x, int y, const std::string& s, const Color& color, bool vertical) {
  for (size_t i = 0; i < s.size(); ++i) {
    const char* rows = glyphRows(s[i]);
    // g, p, q and y are drawn two rows lower: their tails hang below the line.
    const int drop = std::char_traits<char>::find("gpqy", 4, s[i]) ? 2 : 0;
    for (int row = 0; row < 7; ++row)
      for (int column = 0; column < 5; ++column) {
        if (rows[row * 5 + column] != '#') continue;
        for (int dy = 0; dy < kTextScale; ++dy)
          for (int dx = 0; dx < kTextScale; ++dx) {
            const int gx = int(i) * kCharAdvance + column * kTextScale + dx, gy = (row + drop) * kTextScale + dy;
            if (vertical)
              set(x + gy, y - gx, color);
            else
              set(x + gx, y + gy, color);
          }
      }
  }
}

void writePng(const std::string& path, const Canvas& canvas, const std::string& what) {
  try {
    portico::writePng(path, uint32_t(canvas.width()), uint32_t(canvas.height()), canvas.pixels());
  } catch (const std::exception& e) {
    throw std::runtime_error("cannot write the " + what + " to " + path + " (" + e.what() + ")");
  }
}

}  // namespace portico::cli
