// The compact photon record of photon tables, on the wire and in jobs.db:
// 24 bytes (position as floats, power as shared-exponent RGB, direction in
// octahedral coordinates). Records are little-endian PODs, appended to a
// cell's table batch by batch; a map sorts them, so arrival order never
// matters.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "common/transport/photon_map.h"

namespace portico {

struct PhotonRecord {
  float position[3];
  uint32_t power;         // RGBE: 8-bit mantissas, shared 8-bit exponent
  int16_t direction[2];   // octahedral map of the unit direction of travel
  uint8_t bounce;         // 0: first hit after leaving the light (saturates at 255)
  uint8_t reserved;
  uint16_t padding;      // zero; keeps records 4-byte aligned
};
static_assert(sizeof(PhotonRecord) == 24, "photon records are 24 bytes");

inline uint32_t encodeRgbe(const Vec3& c) {
  const float largest = std::max(c.x, std::max(c.y, c.z));
  if (!(largest > 1e-32f)) return 0;
  int exponent;
  const float mantissa = std::frexp(largest, &exponent) * 256.0f / largest;
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
  out[0] = static_cast<int16_t>(std::lround(std::clamp(u, -1.0f, 1.0f) * 32767.0f));
  out[1] = static_cast<int16_t>(std::lround(std::clamp(v, -1.0f, 1.0f) * 32767.0f));
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

inline PhotonRecord toRecord(const StoredPhoton& p) {
  PhotonRecord r{};
  r.position[0] = p.position.x;
  r.position[1] = p.position.y;
  r.position[2] = p.position.z;
  r.power = encodeRgbe(p.power);
  encodeOctahedral(p.direction, r.direction);
  r.bounce = static_cast<uint8_t>(std::min<uint32_t>(p.bounce, 255));
  return r;
}

// pathId is not stored: maps order photons by their record's content.
inline StoredPhoton fromRecord(const PhotonRecord& r) {
  StoredPhoton p;
  p.position = {r.position[0], r.position[1], r.position[2]};
  p.power = decodeRgbe(r.power);
  p.direction = decodeOctahedral(r.direction);
  p.bounce = r.bounce;
  return p;
}

inline std::string packRecords(const std::vector<StoredPhoton>& photons) {
  std::string bytes(photons.size() * sizeof(PhotonRecord), '\0');
  for (size_t i = 0; i < photons.size(); ++i) {
    const PhotonRecord r = toRecord(photons[i]);
    std::memcpy(bytes.data() + i * sizeof r, &r, sizeof r);
  }
  return bytes;
}

// Appends the records in `bytes` to `out`; throws if the size is not a whole number of records.
void unpackRecords(const void* bytes, size_t size, bool includeDirect, std::vector<StoredPhoton>& out);

}  // namespace portico
