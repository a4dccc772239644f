// The compact photon record of photon tables, on the wire and in the
// coordinator's photon files: 8 bytes, one little-endian 64-bit word.
//
// - position (bits 0-41): 14 bits per axis on a lattice over the table's
//   cell (its bounds grown by the photon radius, where copies across
//   portals land: PhotonFrame), so the step is the cell's extent / 16 383:
//   0.6 mm across a 10 m room, 3 mm across a 50 m hall, against search
//   radii of centimetres (the k-th nearest of 128 photons) up to the job's
//   --photon-radius; the estimate averages over the disc, so a step under
//   a tenth of its radius changes nothing visible;
// - one bit (42): whether the photon bounced before (direct photons are
//   left out of the estimate at camera hits);
// - direction (bits 43-52): the surface's normal into it (StoredPhoton),
//   octahedral, both coordinates on 29 levels (-14..14 / 14): exact for
//   the axes and the 45-degree diagonals of walls, floors and an octagon's
//   sides, within 9 degrees elsewhere. Estimates only compare it with
//   their own normal (photons beyond 120 degrees are left out; an
//   irradiance point takes normals within 25 degrees and tilts its disc by
//   the error, a small part of the disc's thickness);
// - power (bits 53-63): a 4-bit exponent e and a mantissa m of 0..4 per
//   channel (the three in 7 bits, base 5), m * unit * 2^(e - 10), unit the
//   job's mean power per emitted photon (photon_power_unit.h): every
//   photon starts near it and bounces only filter its colour. Mantissas
//   are rounded up or down at random (keyed by the photon's path and
//   bounce, so the same bits on every worker) with the odds that keep each
//   channel's expected value exact: the estimate stays unbiased, and the
//   rounding's noise, at most a quarter of a photon's power, averages out
//   over the estimate's 128 photons. A channel above 128 units (the
//   brightest saturated lamp is about ten) is clamped there.
//
// Every deposit is written to its job's photon file once per table it
// lands in (by its worker, or by the coordinator from the worker's Result:
// coordinator/deposit_regions.h) and read once per build of that cell's
// map: each byte of a record is paid for on every copy, and the full
// 101-floor workload stores some 8 G photons.
// Records are appended to a cell's table batch by batch; a map sorts them,
// so arrival order never matters.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "common/rng.h"
#include "common/transport/photon_map.h"

namespace portico {

struct PhotonRecord {
  uint64_t bits;
};
static_assert(sizeof(PhotonRecord) == 8, "photon records are 8 bytes");

// What a cell's table is decoded against: the lattice its positions lie on
// (the cell's bounds grown by the job's photon radius, a millimetre and
// 1/1024 of its largest extent, 2^14 steps per axis) and the job's power unit. Encoder (the worker that
// deposits) and decoder (the worker that builds the cell's map) compute it
// from the same catalogue bounds and job, in the same float operations, so
// records decode bit-identically.
class PhotonFrame {
 public:
  static constexpr uint32_t kBits = 14;
  static constexpr uint32_t kLastStep = (1u << kBits) - 1;
  static constexpr int kExponents = 16;
  static constexpr int kExponentBias = 10;   // mantissa * unit * 2^(e - 10)
  static constexpr uint32_t kLargestMantissa = 4;   // 5 levels per channel

  // Throws std::invalid_argument for bounds that are not a finite box, a
  // radius that is not finite or a power unit that is not a positive
  // normal float.
  PhotonFrame(const Bounds3& cellBounds, float photonRadius, float powerUnit);

  // Points outside the frame are clamped onto its faces (the kernel deposits
  // within a cell's bounds, and copies within the radius of its portals).
  uint64_t encode(const Vec3& p) const;
  Vec3 decode(uint64_t bits) const;
  const Vec3& step() const { return step_; }
  float powerUnit() const { return scales_[kExponentBias]; }
  // unit * 2^(e - kExponentBias)
  float scale(uint32_t exponent) const { return scales_[exponent]; }

 private:
  Vec3 origin_, step_, inverseStep_;
  std::array<float, kExponents> scales_{};
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

namespace photon_bits {
constexpr uint32_t kPositionBits = 3 * PhotonFrame::kBits;   // 42
constexpr uint64_t kBounced = uint64_t{1} << kPositionBits;
constexpr uint32_t kDirectionShift = kPositionBits + 1;       // 43
constexpr uint32_t kDirectionBits = 10;
constexpr int kDirectionSteps = 14;                           // levels -14..14 per coordinate
constexpr uint32_t kDirectionLevels = 2 * kDirectionSteps + 1;
constexpr uint32_t kDirectionCodes = kDirectionLevels * kDirectionLevels;   // 841 of 1024
constexpr uint32_t kExponentShift = kDirectionShift + kDirectionBits;      // 53
constexpr uint32_t kMantissaLevels = PhotonFrame::kLargestMantissa + 1;    // 5
constexpr uint32_t kMantissaCodes = kMantissaLevels * kMantissaLevels * kMantissaLevels;   // 125 of 128
static_assert(kExponentShift + 4 + 7 == 64, "the fields fill the word");
static_assert(kDirectionCodes <= (1u << kDirectionBits) && kMantissaCodes <= 128, "the codes fit their bits");
}  // namespace photon_bits

// The octahedral code of unit vector d (0 .. kDirectionCodes - 1).
inline uint32_t encodeOctahedral(const Vec3& d) {
  const float l1 = std::abs(d.x) + std::abs(d.y) + std::abs(d.z);
  float u = d.x / l1, v = d.y / l1;
  if (d.z < 0) {
    const float ou = u, ov = v;
    u = (1 - std::abs(ov)) * (ou >= 0 ? 1.0f : -1.0f);
    v = (1 - std::abs(ou)) * (ov >= 0 ? 1.0f : -1.0f);
  }
  constexpr float steps = float(photon_bits::kDirectionSteps);
  // Written so that NaN (a zero vector) lands on the middle, +z.
  const auto level = [](float c) {
    return uint32_t(roundHalfAway(c > -1.0f ? std::min(c, 1.0f) * steps : -steps) + photon_bits::kDirectionSteps);
  };
  return level(u) * photon_bits::kDirectionLevels + level(v);
}

// code < kDirectionCodes.
inline Vec3 decodeOctahedral(uint32_t code) {
  constexpr float steps = float(photon_bits::kDirectionSteps);
  float u = (float(code / photon_bits::kDirectionLevels) - steps) / steps;
  float v = (float(code % photon_bits::kDirectionLevels) - steps) / steps;
  const float z = 1 - std::abs(u) - std::abs(v);
  if (z < 0) {
    const float ou = u, ov = v;
    u = (1 - std::abs(ov)) * (ou >= 0 ? 1.0f : -1.0f);
    v = (1 - std::abs(ou)) * (ov >= 0 ? 1.0f : -1.0f);
  }
  return normalize(Vec3(u, v, z));
}

// The power's 11 bits (exponent, then r + 5 g + 25 b), rounded
// at random with odds that keep each channel's expectation: `random` holds
// three independent 21-bit uniforms. Channels must be finite and >= 0.
inline uint32_t encodePower(const Vec3& power, const PhotonFrame& frame, uint64_t random) {
  const float largest = maxComponent(power);
  int exponent = 0;
  frexpOfNormal(largest / (float(PhotonFrame::kLargestMantissa) * frame.powerUnit()), &exponent);
  // The smallest scale at which the largest channel is at most 7 mantissa steps.
  const uint32_t e = uint32_t(std::clamp(exponent + PhotonFrame::kExponentBias, 0, PhotonFrame::kExponents - 1));
  const float inverseScale = 1.0f / frame.scale(e);
  uint32_t code = 0;
  for (int c = 2; c >= 0; --c) {
    const float steps = std::min(std::max(power[c], 0.0f) * inverseScale, float(PhotonFrame::kLargestMantissa));
    const uint32_t whole = uint32_t(steps);
    const float uniform = float((random >> (21 * c)) & 0x1fffffu) * 0x1p-21f;
    const uint32_t mantissa = std::min(whole + (uniform < steps - float(whole) ? 1u : 0u), PhotonFrame::kLargestMantissa);
    code = code * photon_bits::kMantissaLevels + mantissa;
  }
  return e | code << 4;
}

// bits >> 4 < kMantissaCodes.
inline Vec3 decodePower(uint32_t bits, const PhotonFrame& frame) {
  const float scale = frame.scale(bits & 0xfu);
  constexpr uint32_t levels = photon_bits::kMantissaLevels;
  const uint32_t code = bits >> 4;
  return {float(code % levels) * scale, float(code / levels % levels) * scale, float(code / (levels * levels)) * scale};
}

// The random bits of a photon's power rounding: its own, apart from every
// other use of its path's random numbers (a copy across a portal rounds as
// the original does).
inline uint64_t powerRoundingBits(const StoredPhoton& p) {
  return mix64(mix64(p.pathId ^ 0x510e527fade682d1ull) ^ p.bounce);
}

// The photon's position must be finite (the kernel drops others before).
inline PhotonRecord toRecord(const StoredPhoton& p, const PhotonFrame& frame) {
  return {frame.encode(p.position) | (p.bounce > 0 ? photon_bits::kBounced : 0) |
          uint64_t(encodeOctahedral(p.direction)) << photon_bits::kDirectionShift |
          uint64_t(encodePower(p.power, frame, powerRoundingBits(p))) << photon_bits::kExponentShift};
}

inline uint32_t directionCode(const PhotonRecord& r) {
  return uint32_t(r.bits >> photon_bits::kDirectionShift) & ((1u << photon_bits::kDirectionBits) - 1);
}

// Whether the record's codes are ones an encoder writes (not a damaged file's).
inline bool isWellFormed(const PhotonRecord& r) {
  return directionCode(r) < photon_bits::kDirectionCodes &&
         (r.bits >> (photon_bits::kExponentShift + 4)) < photon_bits::kMantissaCodes;
}

// pathId is not stored: maps order photons by their record's content.
// bounce comes back as 0 (direct) or 1 (bounced at least once). The record
// must be well-formed.
inline StoredPhoton fromRecord(const PhotonRecord& r, const PhotonFrame& frame) {
  StoredPhoton p;
  p.position = frame.decode(r.bits);
  p.power = decodePower(uint32_t(r.bits >> photon_bits::kExponentShift), frame);
  p.direction = decodeOctahedral(directionCode(r));
  p.bounce = (r.bits & photon_bits::kBounced) ? 1 : 0;
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

// Appends the records in `bytes` to `out`, leaving out those that are not
// well-formed (a damaged file); throws if the size is not a whole number of
// records.
void unpackRecords(const void* bytes, size_t size, const PhotonFrame& frame, bool includeDirect,
                   std::vector<StoredPhoton>& out);

}  // namespace portico
