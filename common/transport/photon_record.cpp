#include "common/transport/photon_record.h"

#include <fmt/format.h>

#include <stdexcept>

namespace portico {

PhotonFrame::PhotonFrame(const Bounds3& cellBounds, float photonRadius) {
  if (!isFinite(cellBounds.lo) || !isFinite(cellBounds.hi) || cellBounds.empty())
    throw std::invalid_argument(fmt::format("photon frame: cell bounds ({}, {}, {}) - ({}, {}, {}) are not a finite box",
                                            cellBounds.lo.x, cellBounds.lo.y, cellBounds.lo.z, cellBounds.hi.x,
                                            cellBounds.hi.y, cellBounds.hi.z));
  if (!std::isfinite(photonRadius))
    throw std::invalid_argument(fmt::format("photon frame: photon radius {} is not finite", photonRadius));
  // The millimetre keeps a flat cell's lattice non-degenerate and covers
  // hit points a rounding error outside the bounds.
  const Vec3 margin(std::max(photonRadius, 0.0f) + 1e-3f);
  origin_ = cellBounds.lo - margin;
  step_ = (cellBounds.hi + margin - origin_) / float(kLastStep);
  inverseStep_ = Vec3(1.0f) / step_;
}

uint64_t PhotonFrame::encode(const Vec3& p) const {
  uint64_t bits = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const float steps = (p[axis] - origin_[axis]) * inverseStep_[axis];
    // Written so that NaN lands on 0.
    const float clamped = steps > 0.0f ? std::min(steps, float(kLastStep)) : 0.0f;
    bits |= uint64_t(uint32_t(clamped + 0.5f)) << (kBits * axis);
  }
  return bits;
}

Vec3 PhotonFrame::decode(uint64_t bits) const {
  Vec3 p;
  for (int axis = 0; axis < 3; ++axis) p[axis] = origin_[axis] + float((bits >> (kBits * axis)) & kLastStep) * step_[axis];
  return p;
}

void unpackRecords(const void* bytes, size_t size, const PhotonFrame& frame, bool includeDirect,
                   std::vector<StoredPhoton>& out) {
  if (size % sizeof(PhotonRecord) != 0)
    throw std::runtime_error(fmt::format("photon table: {} bytes is not a whole number of {}-byte records", size,
                                         sizeof(PhotonRecord)));
  const size_t count = size / sizeof(PhotonRecord);
  out.reserve(out.size() + count);
  for (size_t i = 0; i < count; ++i) {
    PhotonRecord r;
    std::memcpy(&r, static_cast<const char*>(bytes) + i * sizeof r, sizeof r);
    if (!(r.position & kBouncedBit) && !includeDirect) continue;
    // Positions decode finite by construction; power may not (a bad file).
    StoredPhoton p = fromRecord(r, frame);
    if (isFinite(p.power)) out.push_back(p);
  }
}

}  // namespace portico
