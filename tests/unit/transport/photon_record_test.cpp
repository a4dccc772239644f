#include "common/transport/photon_record.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace portico {
namespace {

// A 50 x 6 x 35 m cell, off the origin.
const Bounds3 kCell(Vec3(-30.0f, -2.0f, 5.0f), Vec3(20.0f, 4.0f, 40.0f));
constexpr float kRadius = 0.5f;
constexpr float kUnit = 3.7e-5f;   // the job's power unit

TEST(PhotonRecord, RoundTripsWithinHalfALatticeStep) {
  const PhotonFrame frame(kCell, kRadius, kUnit);
  // 50 m + 2 radii over 2^14 steps: ~3.1 mm.
  EXPECT_LT(frame.step().x, 3.2e-3f);
  std::mt19937 random(5);
  std::uniform_real_distribution<float> unit(-1, 1), along(0, 1), power(1e-3f, 3.0f);
  for (int i = 0; i < 10000; ++i) {
    StoredPhoton p;
    // Inside the cell, or (a copy across a portal) up to the radius outside it.
    for (int axis = 0; axis < 3; ++axis)
      p.position[axis] = kCell.lo[axis] - kRadius + (kCell.hi[axis] - kCell.lo[axis] + 2 * kRadius) * along(random);
    p.direction = normalize(Vec3(unit(random), unit(random), unit(random)));
    const float base = power(random) * kUnit;
    p.power = {base, base * 0.5f * (1 + unit(random)), base * 0.25f * (1 + unit(random))};
    p.bounce = static_cast<uint16_t>(i % 300);
    p.pathId = uint64_t(i) * 7919;
    const PhotonRecord r = toRecord(p, frame);
    const StoredPhoton q = fromRecord(r, frame);
    for (int axis = 0; axis < 3; ++axis) {
      // Half a step, and the float rounding of coordinates up to 40 m.
      const float tolerance = 0.5f * frame.step()[axis] + 8e-6f;
      EXPECT_NEAR(q.position[axis], p.position[axis], tolerance) << i << " axis " << axis;
    }
    // Within 9 degrees.
    EXPECT_GT(dot(q.direction, p.direction), 0.9877f) << i;
    // Each channel rounds to one of the two mantissa steps around it: the
    // step is at most half the largest channel.
    const float largest = maxComponent(p.power);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(q.power[c], p.power[c], largest / 2.0f * 1.0001f) << i << " channel " << c;
    EXPECT_EQ(q.bounce, p.bounce > 0 ? 1 : 0);
    // A decoded photon is a lattice point: it encodes to the same position,
    // so a table re-encoded anywhere stays bit-identical.
    const PhotonRecord again = toRecord(q, frame);
    EXPECT_EQ(again.bits & ((uint64_t{1} << 42) - 1), r.bits & ((uint64_t{1} << 42) - 1)) << i;
    EXPECT_EQ(fromRecord(again, frame).direction, q.direction) << i;
  }
}

TEST(PhotonRecord, AxesAndDiagonalsOfWallsAreExact) {
  const PhotonFrame frame(kCell, kRadius, kUnit);
  const float h = std::sqrt(0.5f);
  for (const Vec3& n : {Vec3(1, 0, 0), Vec3(-1, 0, 0), Vec3(0, 1, 0), Vec3(0, -1, 0), Vec3(0, 0, 1), Vec3(0, 0, -1),
                        Vec3(h, h, 0), Vec3(-h, h, 0), Vec3(h, -h, 0), Vec3(-h, -h, 0), Vec3(h, 0, h),
                        Vec3(0, -h, -h)}) {
    StoredPhoton p;
    p.position = Vec3(0.0f, 1.0f, 10.0f);
    p.direction = n;
    const Vec3 d = fromRecord(toRecord(p, frame), frame).direction;
    for (int axis = 0; axis < 3; ++axis) EXPECT_NEAR(d[axis], n[axis], 1e-6f) << n.x << " " << n.y << " " << n.z;
  }
}

// The estimate sums photons' powers: rounding must keep each channel's
// mean, whatever the power's size against the job's unit.
TEST(PhotonRecord, PowerRoundingKeepsTheMeanOfEveryChannel) {
  const PhotonFrame frame(kCell, kRadius, kUnit);
  for (const Vec3& power : {Vec3(1.0f, 0.8f, 0.3f) * kUnit, Vec3(0.37f, 0.011f, 0.2f) * kUnit,
                            Vec3(9.4f, 0.0f, 0.0f) * kUnit, Vec3(3e-4f, 1e-4f, 2e-4f) * kUnit,
                            Vec3(100.0f, 60.0f, 30.0f) * kUnit}) {
    double sum[3] = {0, 0, 0};
    constexpr int kPhotons = 200000;
    for (int i = 0; i < kPhotons; ++i) {
      StoredPhoton p;
      p.position = Vec3(1.0f, 1.0f, 10.0f);
      p.direction = Vec3(0, 0, -1);
      p.power = power;
      p.pathId = uint64_t(i);
      p.bounce = uint16_t(i % 3);
      const Vec3 q = fromRecord(toRecord(p, frame), frame).power;
      for (int c = 0; c < 3; ++c) sum[c] += q[c];
    }
    for (int c = 0; c < 3; ++c) {
      // Each record's error is under one mantissa step (half the largest
      // channel at most, or the smallest step for powers below it):
      // the mean's standard error is a tenth of this over 200 000 photons.
      EXPECT_NEAR(sum[c] / kPhotons, power[c], 3e-3 * std::max(maxComponent(power), frame.scale(0)))
          << c << " of " << power.x;
    }
  }
  // Zero stays zero.
  StoredPhoton dark;
  dark.position = Vec3(1.0f, 1.0f, 10.0f);
  dark.direction = Vec3(0, 0, 1);
  EXPECT_EQ(fromRecord(toRecord(dark, frame), frame).power, Vec3(0));
}

TEST(PhotonRecord, ClampsPointsOutsideItsFrameAndRejectsFramesThatAreNotBoxes) {
  const PhotonFrame frame(kCell, kRadius, kUnit);
  StoredPhoton far;
  far.position = Vec3(1000.0f, -1000.0f, 20.0f);
  far.direction = Vec3(0, 1, 0);
  const Vec3 clamped = fromRecord(toRecord(far, frame), frame).position;
  // The frame's faces: the radius, a millimetre and 1/1024 of the largest extent (50 m) beyond the cell.
  const float margin = kRadius + 1e-3f + 50.0f / 1024.0f;
  EXPECT_NEAR(clamped.x, kCell.hi.x + margin, 2e-3f);
  EXPECT_NEAR(clamped.y, kCell.lo.y - margin, 2e-3f);
  EXPECT_NEAR(clamped.z, 20.0f, 0.5f * frame.step().z);
  StoredPhoton nan = far;
  nan.position.x = std::numeric_limits<float>::quiet_NaN();
  EXPECT_TRUE(isFinite(fromRecord(toRecord(nan, frame), frame).position));

  // A flat cell (a floor alone) still has a lattice across its thickness.
  const PhotonFrame flat(Bounds3(Vec3(0.0f), Vec3(10.0f, 0.0f, 10.0f)), 0.0f, kUnit);
  EXPECT_GT(flat.step().y, 0.0f);
  StoredPhoton onFloor = far;
  onFloor.position = Vec3(3.0f, 0.0f, 7.0f);
  EXPECT_NEAR(fromRecord(toRecord(onFloor, flat), flat).position.y, 0.0f, 1e-6f);
  // A zero direction (never deposited) still decodes to a unit vector.
  StoredPhoton noDirection = far;
  noDirection.direction = Vec3(0.0f);
  EXPECT_NEAR(length(fromRecord(toRecord(noDirection, frame), frame).direction), 1.0f, 1e-6f);

  const float inf = std::numeric_limits<float>::infinity();
  EXPECT_THROW(PhotonFrame(Bounds3(), kRadius, kUnit), std::invalid_argument);   // empty
  EXPECT_THROW(PhotonFrame(Bounds3(Vec3(0.0f), Vec3(inf)), kRadius, kUnit), std::invalid_argument);
  EXPECT_THROW(PhotonFrame(kCell, std::numeric_limits<float>::quiet_NaN(), kUnit), std::invalid_argument);
  EXPECT_THROW(PhotonFrame(kCell, kRadius, 0.0f), std::invalid_argument);
  EXPECT_THROW(PhotonFrame(kCell, kRadius, inf), std::invalid_argument);
  EXPECT_THROW(PhotonFrame(kCell, kRadius, 3e38f), std::invalid_argument);
}

TEST(PhotonRecord, UnpackFiltersDirectPhotonsAndRejectsTornTables) {
  const PhotonFrame frame(kCell, kRadius, kUnit);
  std::vector<StoredPhoton> photons(3);
  for (int i = 0; i < 3; ++i) {
    photons[i].position = Vec3(float(i), 0.0f, 10.0f);
    photons[i].direction = {0, -1, 0};
    photons[i].power = Vec3(1);
    photons[i].bounce = static_cast<uint16_t>(i);
  }
  const std::string bytes = packRecords(photons, frame);
  ASSERT_EQ(bytes.size(), 3 * sizeof(PhotonRecord));
  std::vector<StoredPhoton> all, indirect;
  unpackRecords(bytes.data(), bytes.size(), frame, true, all);
  unpackRecords(bytes.data(), bytes.size(), frame, false, indirect);
  EXPECT_EQ(all.size(), 3u);
  EXPECT_EQ(indirect.size(), 2u);
  EXPECT_THROW(unpackRecords(bytes.data(), bytes.size() - 1, frame, true, all), std::runtime_error);
  // A record with a direction code no encoder writes (a damaged file) is left out.
  std::string damaged = bytes;
  damaged[5] = char(0xff);   // bits 40-47: the direction's low bits
  damaged[6] = char(0x1f);   // bits 48-52: its high bits
  // And one with a power code no encoder writes.
  damaged[15] = char(0xff);   // bits 57-63 of the second: the mantissas
  std::vector<StoredPhoton> kept;
  unpackRecords(damaged.data(), damaged.size(), frame, true, kept);
  EXPECT_EQ(kept.size(), 1u);
}

TEST(PhotonRecord, ZeroAndTinyPowersStayFinite) {
  const PhotonFrame frame(kCell, kRadius, kUnit);
  StoredPhoton p;
  p.position = Vec3(0.0f, 1.0f, 10.0f);
  p.direction = Vec3(0, 0, 1);
  for (const float tiny : {1e-30f, 1e-40f, 0.0f}) {
    p.power = Vec3(tiny, 0, 0);
    EXPECT_TRUE(isFinite(fromRecord(toRecord(p, frame), frame).power)) << tiny;
  }
}

}  // namespace
}  // namespace portico

namespace portico {
namespace {
TEST(PhotonRecord, ItsRoundingAndExponentAreTheLibrarysBitForBit) {
  // Every float with random bits (of every exponent), and those next to
  // halves, where rounding decides.
  std::mt19937 random(7);
  std::vector<float> values{0.0f, -0.0f, 0.5f, -0.5f, 1.5f, -2.5f, 32767.0f, -32767.0f, 1e-32f, 1e-40f,
                            std::numeric_limits<float>::infinity(), std::numeric_limits<float>::quiet_NaN()};
  for (int i = 0; i < 2'000'000; ++i) {
    const uint32_t bits = uint32_t(random());
    float x;
    std::memcpy(&x, &bits, sizeof x);
    values.push_back(x);
  }
  for (int k = -33000; k <= 33000; ++k) {
    const float half = float(k) + 0.5f;
    values.insert(values.end(), {half, std::nextafter(half, 0.0f), std::nextafter(half, 1e9f),
                                 std::nextafter(half, -1e9f), float(k) * 0.999f, float(k) * 1.0001f});
  }
  int checked = 0;
  for (const float x : values) {
    if (std::isfinite(x) && std::abs(x) < 1e9f) {
      ASSERT_EQ(roundHalfAway(x), std::lround(x)) << x;
      ++checked;
    }
    int expected = 0, got = 0;
    const float m = std::frexp(x, &expected), n = frexpOfNormal(x, &got);
    if (std::isnan(x)) {
      EXPECT_TRUE(std::isnan(n));
      continue;
    }
    ASSERT_EQ(std::memcmp(&m, &n, sizeof m), 0) << x;
    if (std::isfinite(x)) ASSERT_EQ(got, expected) << x;
  }
  EXPECT_GT(checked, 400000);
}
}  // namespace
}  // namespace portico
