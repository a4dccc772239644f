// The pixels through which the camera may see an emitter of its own cell:
// a camera ray's emission rays (cell_kernel.h) find nothing to add in any
// other pixel, so there they are not traced, and no pixel's value changes.
//
// Each emissive triangle of the cell is projected onto the image and the
// box of its corners' pixels, grown by a pixel on every side (rounding of
// the projection against CameraModel::direction), is marked. Where that
// cannot bound what the camera sees, every pixel is marked: a triangle
// reaching behind the camera, or a glass pane in the cell (an emission ray
// reflected off it may meet an emitter anywhere). A luminaire's luminous
// opening (scene_types.h) is marked by the box of its world bounds'
// corners, as a triangle's.
#pragma once

#include <cstdint>
#include <vector>

#include "common/scene/store/cell_geometry.h"
#include "common/scene/store/scene_types.h"
#include "common/transport/camera_model.h"

namespace portico {

class EmitterPixels {
 public:
  EmitterPixels(const CameraModel& camera, uint32_t width, uint32_t height, const CellGeometry& cell,
                const std::vector<Material>& materials, const std::vector<Bounds3>& luminaireOpenings = {});
  bool mayShowEmitter(uint32_t pixel) const { return everyPixel_ || marked_[pixel]; }
  // Pixels marked (for tests and statistics).
  uint64_t markedCount() const;

 private:
  void markBox(float minX, float minY, float maxX, float maxY);
  // Marks the pixels of the corners' projection (everyPixel_ when one
  // cannot be projected); none when all lie behind the camera's plane.
  template <size_t N>
  void markCorners(const CameraModel& camera, const Vec3 (&corners)[N], float minDepth);

  uint32_t width_, height_;
  bool everyPixel_ = false;
  std::vector<bool> marked_;
};

}  // namespace portico
