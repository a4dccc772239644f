#include "common/transport/emitter_pixels.h"

#include <algorithm>
#include <cmath>
#include <iterator>

namespace portico {

EmitterPixels::EmitterPixels(const CameraModel& camera, uint32_t width, uint32_t height, const CellGeometry& cell,
                             const std::vector<Material>& materials, const std::vector<Bounds3>& luminaireOpenings)
    : width_(width), height_(height) {
  const MeshView& mesh = cell.mesh();
  for (uint32_t primitive = 0; primitive < mesh.triangleCount && !everyPixel_; ++primitive) {
    if (materials[cell.material(primitive)].glass()) everyPixel_ = true;
  }
  if (everyPixel_) return;
  marked_.assign(size_t{width} * height, false);
  // A corner this near the camera's plane (or behind it) projects far off
  // the image or not at all: the triangle is taken to cover every pixel.
  const float minDepth = 1e-4f * std::max(1.0f, length(cell.bounds().diagonal()));
  for (uint32_t primitive = 0; primitive < mesh.triangleCount; ++primitive) {
    if (!materials[cell.material(primitive)].emissive()) continue;
    Vec3 corners[3];
    mesh.triangle(primitive, corners[0], corners[1], corners[2]);
    markCorners(camera, corners, minDepth);
    if (everyPixel_) return;
  }
  for (const Bounds3& box : luminaireOpenings) {
    Vec3 corners[8];
    for (int k = 0; k < 8; ++k)
      corners[k] = Vec3(k & 1 ? box.hi.x : box.lo.x, k & 2 ? box.hi.y : box.lo.y, k & 4 ? box.hi.z : box.lo.z);
    markCorners(camera, corners, minDepth);
    if (everyPixel_) return;
  }
}

template <size_t N>
void EmitterPixels::markCorners(const CameraModel& camera, const Vec3 (&corners)[N], float minDepth) {
  // Wholly behind the camera's plane: no camera ray (each has a positive
  // part along the axis) meets it.
  if (std::all_of(std::begin(corners), std::end(corners), [&](const Vec3& c) { return camera.depthOf(c) <= 0; }))
    return;
  float minX = kInfinity, minY = kInfinity, maxX = -kInfinity, maxY = -kInfinity;
  for (const Vec3& corner : corners) {
    float px, py;
    if (!camera.project(corner, minDepth, px, py) || !std::isfinite(px) || !std::isfinite(py)) {
      everyPixel_ = true;
      return;
    }
    minX = std::min(minX, px), maxX = std::max(maxX, px);
    minY = std::min(minY, py), maxY = std::max(maxY, py);
  }
  markBox(minX, minY, maxX, maxY);
}

void EmitterPixels::markBox(float minX, float minY, float maxX, float maxY) {
  // One pixel more on every side; clamped to the image (a box wholly off it
  // marks nothing).
  const float x0 = std::floor(minX) - 1, y0 = std::floor(minY) - 1;
  const float x1 = std::floor(maxX) + 1, y1 = std::floor(maxY) + 1;
  if (x1 < 0 || y1 < 0 || x0 >= float(width_) || y0 >= float(height_)) return;
  const uint32_t left = static_cast<uint32_t>(std::max(x0, 0.0f));
  const uint32_t top = static_cast<uint32_t>(std::max(y0, 0.0f));
  const uint32_t right = static_cast<uint32_t>(std::min(x1, float(width_ - 1)));
  const uint32_t bottom = static_cast<uint32_t>(std::min(y1, float(height_ - 1)));
  for (uint32_t y = top; y <= bottom; ++y)
    for (uint32_t x = left; x <= right; ++x) marked_[size_t{y} * width_ + x] = true;
}

uint64_t EmitterPixels::markedCount() const {
  if (everyPixel_) return uint64_t{width_} * height_;
  return static_cast<uint64_t>(std::count(marked_.begin(), marked_.end(), true));
}

}  // namespace portico
