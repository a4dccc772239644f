#include "common/transport/photon_record.h"

#include <fmt/format.h>

#include <stdexcept>

namespace portico {

PhotonFrame::PhotonFrame(const Bounds3& cellBounds, float photonRadius, float powerUnit) {
  if (!isFinite(cellBounds.lo) || !isFinite(cellBounds.hi) || cellBounds.empty())
    throw std::invalid_argument(fmt::format("photon frame: cell bounds ({}, {}, {}) - ({}, {}, {}) are not a finite box",
                                            cellBounds.lo.x, cellBounds.lo.y, cellBounds.lo.z, cellBounds.hi.x,
                                            cellBounds.hi.y, cellBounds.hi.z));
  if (!std::isfinite(photonRadius))
    throw std::invalid_argument(fmt::format("photon frame: photon radius {} is not finite", photonRadius));
  if (!std::isnormal(powerUnit) || !(powerUnit > 0))
    throw std::invalid_argument(fmt::format("photon frame: power unit {} is not a positive normal float", powerUnit));
  for (int e = 0; e < kExponents; ++e) scales_[size_t(e)] = std::ldexp(powerUnit, e - kExponentBias);
  if (!std::isfinite(scales_.back()))
    throw std::invalid_argument(fmt::format("photon frame: power unit {} is too large", powerUnit));
  // The millimetre keeps a flat cell's lattice non-degenerate; a 1/1024 of
  // the cell's largest extent (16 steps) keeps hit points a rounding error
  // outside the bounds, and copies at the photon radius from their portal,
  // off the lattice's faces, where clamping would begin.
  const Vec3 extent = cellBounds.hi - cellBounds.lo;
  const float largest = std::max(extent.x, std::max(extent.y, extent.z));
  const Vec3 margin(std::max(photonRadius, 0.0f) + 1e-3f + largest * 0x1p-10f);
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
    if (!(r.bits & photon_bits::kBounced) && !includeDirect) continue;
    // Positions and powers decode finite by construction.
    if (isWellFormed(r)) out.push_back(fromRecord(r, frame));
  }
}

}  // namespace portico
