// Pinhole camera by look-at, with the conventions of tests/scenes/*/scene.json:
// fov_y is the full vertical angle, pixels are square, x grows to the right,
// row 0 is the top row.
#pragma once

#include <cmath>

#include "common/scene/store/scene_types.h"

namespace portico {

class CameraModel {
 public:
  CameraModel(const Camera& camera, uint32_t width, uint32_t height)
      : origin_(camera.origin), width_(width), height_(height) {
    forward_ = normalize(camera.target - camera.origin);
    right_ = normalize(cross(forward_, camera.up));
    up_ = cross(right_, forward_);
    tanY_ = std::tan(0.5f * camera.fovYDegrees * kPi / 180.0f);
    tanX_ = tanY_ * float(width) / float(height);
  }
  const Vec3& origin() const { return origin_; }
  // Unit direction through continuous pixel position (px, py); (0,0) is the top-left corner.
  Vec3 direction(float px, float py) const {
    const float sx = (2.0f * px / float(width_) - 1.0f) * tanX_;
    const float sy = (1.0f - 2.0f * py / float(height_)) * tanY_;
    return normalize(forward_ + right_ * sx + up_ * sy);
  }
  // How far `point` lies in front of the camera, along its axis.
  float depthOf(const Vec3& point) const { return dot(point - origin_, forward_); }
  // The continuous pixel position (px, py) that direction() aims through
  // towards `point`; false for a point not in front of the camera (at least
  // `minDepth` along its axis).
  bool project(const Vec3& point, float minDepth, float& px, float& py) const {
    const Vec3 offset = point - origin_;
    const float depth = depthOf(point);
    if (!(depth >= minDepth)) return false;
    px = (dot(offset, right_) / depth / tanX_ + 1.0f) * 0.5f * float(width_);
    py = (1.0f - dot(offset, up_) / depth / tanY_) * 0.5f * float(height_);
    return true;
  }

 private:
  Vec3 origin_, forward_, right_, up_;
  uint32_t width_, height_;
  float tanX_ = 1, tanY_ = 1;
};

}  // namespace portico
