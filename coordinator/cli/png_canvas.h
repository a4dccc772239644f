// An RGB raster for the pictures `portico` draws itself (`bench --plot`,
// `scene plan`): filled rectangles, lines (solid or dashed), text in a
// built-in 5x7 bitmap font, written as PNG with libpng. No OpenImageIO (it
// would add ~160 ms to every `portico` start).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace portico::cli {

using Color = std::array<uint8_t, 3>;
constexpr Color kBlack{0, 0, 0}, kGrey{120, 120, 120}, kLightGrey{225, 225, 225}, kWhite{255, 255, 255};
constexpr int kTextScale = 2;                  // font pixels are 2x2 canvas pixels
constexpr int kCharAdvance = 6 * kTextScale;   // 5 columns and a gap
constexpr int kTextHeight = 7 * kTextScale;    // without descenders

// Width in pixels of `s` drawn by Canvas::text.
int textWidth(const std::string& s);

class Canvas {
 public:
  Canvas(int width, int height) : width_(width), height_(height), pixels_(size_t(width) * height * 3, 255) {}
  int width() const { return width_; }
  int height() const { return height_; }
  const std::vector<uint8_t>& pixels() const { return pixels_; }

  // Pixels outside the canvas are ignored, so callers need not clip.
  void set(int x, int y, const Color& color) {
    if (x < 0 || y < 0 || x >= width_ || y >= height_) return;
    uint8_t* p = &pixels_[(size_t(y) * width_ + x) * 3];
    p[0] = color[0], p[1] = color[1], p[2] = color[2];
  }
  // The rectangle with corners (x0, y0) and (x1, y1), both included.
  void fill(int x0, int y0, int x1, int y1, const Color& color);
  // A line `thickness` pixels wide; dashed lines alternate 9 pixels on, 6 off.
  void line(double x0, double y0, double x1, double y1, const Color& color, int thickness, bool dashed);
  void resetDash() { dashPhase_ = 0; }
  // Text with its top-left corner at (x, y); vertical text reads bottom to top.
  void text(int x, int y, const std::string& s, const Color& color, bool vertical = false);

 private:
  int width_, height_;
  std::vector<uint8_t> pixels_;
  double dashPhase_ = 0;
};

// Writes `canvas` as an 8-bit RGB PNG. Throws std::runtime_error naming the
// file ("cannot write the <what> to <path>") when it cannot be written.
void writePng(const std::string& path, const Canvas& canvas, const std::string& what);

}  // namespace portico::cli
