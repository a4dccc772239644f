// The compact photon record of photon tables, on the wire and in the
// coordinator's photon files: 16 bytes.
//
// - position: 21 bits per axis on a lattice over the table's cell (its
//   bounds grown by the photon radius, where copies across portals land:
//   PhotonFrame), so the step is the cell's extent / 2^21 — 24 um across a
//   50 m hall, far below any search radius;
// - one bit: whether the photon bounced before (direct photons are left
//   out of the estimate at camera hits);
// - power as shared-exponent RGB, direction (into the surface, along its
//   lit side's normal: StoredPhoton) in octahedral coordinates.
//
// Every deposit is written to its job's photon file once per table it
// lands in (by its worker, or by the coordinator from the worker's Result:
// coordinator/deposit_regions.h) and read once per build of that cell's
// map: a 24-byte record of floats makes every one of those copies half as
// large again (the coordinator's photon-pass CPU was 8 % lower with 16
// bytes, when every record passed through it).
// Records are little-endian PODs, appended to a cell's table batch by batch;
// a map sorts them, so arrival order never matters.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "common/transport/photon_map.h"

namespace portico {

struct PhotonRecord {
  uint64_t position;      // x | y << 21 | z << 42 on the frame's lattice; bit 63: bounced
  uint32_t power;         // RGBE: 8-bit mantissas, shared 8-bit exponent
  int16_t direction[2];   // octahedral map of StoredPhoton::direction
};
static_assert(sizeof(PhotonRecord) == 16, "photon records are 16 bytes");

// The lattice photon positions of one cell's table are stored on: the
// cell's bounds grown by the job's photon radius (and a millimetre), 2^21
// steps per axis. Encoder (the worker that deposits) and decoder (the worker
// that builds the cell's map) compute it from the same catalogue bounds and
// job spec, in the same float operations, so positions decode bit-identically.
class PhotonFrame {
 public:
  static constexpr uint32_t kBits = 21;
  static constexpr uint32_t kLastStep = (1u << kBits) - 1;

  // Throws std::invalid_argument for bounds that are not a finite box or a
  // radius that is not finite.
  PhotonFrame(const Bounds3& cellBounds, float photonRadius);

  // Points outside the frame are clamped onto its faces (the kernel deposits
  // within a cell's bounds, and copies within the radius of its portals).
  uint64_t encode(const Vec3& p) const;
  Vec3 decode(uint64_t bits) const;
  const Vec3& step() const { return step_; }

 private:
  Vec3 origin_, step_, inverseStep_;
};

// std::frexp and std::lround, bit for bit, without their library calls: the
// kernel encodes every deposit (and each copy across a portal) with them,
// and the calls were a twentieth of a worker's photon-pass CPU.
inline float frexpOfNormal(float x, int* exponent) {
  uint32_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  const uint32_t biased = (bits >> 23) & 0xffu;
  if (biased == 0 || biased == 0xffu) return std::frexp(x, exponent);   // zero, subnormal, inf, NaN
  *exponent = int(biased) - 126;
  bits = (bits & 0x807fffffu) | (126u << 23);
  float mantissa;
  std::memcpy(&mantissa, &bits, sizeof mantissa);
  return mantissa;
}

// Half away from zero, as std::lround. x - trunc(x) is exact in float, so
// the comparison with 0.5 decides as lround does.
inline long roundHalfAway(float x) {
  if (!(std::abs(x) < 1073741824.0f)) return std::lround(x);   // large, inf, NaN
  const int32_t whole = int32_t(x);   // toward zero
  const float fraction = x - float(whole);
  return long(whole) + (fraction >= 0.5f ? 1 : fraction <= -0.5f ? -1 : 0);
}

inline uint32_t encodeRgbe(const Vec3& c) {
  const float largest = std::max(c.x, std::max(c.y, c.z));
  if (!(largest > 1e-32f)) return 0;
  int exponent;
  const float mantissa = frexpOfNormal(largest, &exponent) * 256.0f / largest;
  auto channel = [&](float v) { return static_cast<uint32_t>(std::max(0.0f, v * mantissa)); };
  return channel(c.x) | channel(c.y) << 8 | channel(c.z) << 16 | static_cast<uint32_t>(exponent + 128) << 24;
}

inline Vec3 decodeRgbe(uint32_t rgbe) {
  const uint32_t e = rgbe >> 24;
  if (e == 0) return Vec3(0);
  const float scale = std::ldexp(1.0f, int(e) - (128 + 8));
  // +0.5: the centre of each mantissa step, so rounding is unbiased.
  return {((rgbe & 0xff) + 0.5f) * scale, (((rgbe >> 8) & 0xff) + 0.5f) * scale,
          (((rgbe >> 16) & 0xff) + 0.5f) * scale};
}

inline void encodeOctahedral(const Vec3& d, int16_t out[2]) {
  const float l1 = std::abs(d.x) + std::abs(d.y) + std::abs(d.z);
  float u = d.x / l1, v = d.y / l1;
  if (d.z < 0) {
    const float ou = u, ov = v;
    u = (1 - std::abs(ov)) * (ou >= 0 ? 1.0f : -1.0f);
    v = (1 - std::abs(ou)) * (ov >= 0 ? 1.0f : -1.0f);
  }
  out[0] = static_cast<int16_t>(roundHalfAway(std::clamp(u, -1.0f, 1.0f) * 32767.0f));
  out[1] = static_cast<int16_t>(roundHalfAway(std::clamp(v, -1.0f, 1.0f) * 32767.0f));
}

inline Vec3 decodeOctahedral(const int16_t in[2]) {
  float u = in[0] / 32767.0f, v = in[1] / 32767.0f;
  const float z = 1 - std::abs(u) - std::abs(v);
  if (z < 0) {
    const float ou = u, ov = v;
    u = (1 - std::abs(ov)) * (ou >= 0 ? 1.0f : -1.0f);
    v = (1 - std::abs(ou)) * (ov >= 0 ? 1.0f : -1.0f);
  }
  return normalize(Vec3(u, v, z));
}

constexpr uint64_t kBouncedBit = uint64_t{1} << 63;

// The photon's position must be finite (the kernel drops others before).
inline PhotonRecord toRecord(const StoredPhoton& p, const PhotonFrame& frame) {
  PhotonRecord r{};
  r.position = frame.encode(p.position) | (p.bounce > 0 ? kBouncedBit : 0);
  r.power = encodeRgbe(p.power);
  encodeOctahedral(p.direction, r.direction);
  return r;
}

// pathId is not stored: maps order photons by their record's content.
// bounce comes back as 0 (direct) or 1 (bounced at least once).
inline StoredPhoton fromRecord(const PhotonRecord& r, const PhotonFrame& frame) {
  StoredPhoton p;
  p.position = frame.decode(r.position);
  p.power = decodeRgbe(r.power);
  p.direction = decodeOctahedral(r.direction);
  p.bounce = (r.position & kBouncedBit) ? 1 : 0;
  return p;
}

inline std::string packRecords(const std::vector<StoredPhoton>& photons, const PhotonFrame& frame) {
  std::string bytes(photons.size() * sizeof(PhotonRecord), '\0');
  for (size_t i = 0; i < photons.size(); ++i) {
    const PhotonRecord r = toRecord(photons[i], frame);
    std::memcpy(bytes.data() + i * sizeof r, &r, sizeof r);
  }
  return bytes;
}

// Appends the records in `bytes` to `out`; throws if the size is not a whole number of records.
void unpackRecords(const void* bytes, size_t size, const PhotonFrame& frame, bool includeDirect,
                   std::vector<StoredPhoton>& out);

}  // namespace portico
