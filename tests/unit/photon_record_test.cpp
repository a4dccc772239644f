#include "common/transport/photon_record.h"

#include <gtest/gtest.h>

#include <random>

namespace portico {
namespace {

TEST(PhotonRecord, RoundTripsWithinItsPrecision) {
  std::mt19937 random(5);
  std::uniform_real_distribution<float> unit(-1, 1), power(1e-6f, 3.0f);
  for (int i = 0; i < 10000; ++i) {
    StoredPhoton p;
    p.position = {unit(random) * 100, unit(random) * 100, unit(random) * 100};
    p.direction = normalize(Vec3(unit(random), unit(random), unit(random)));
    const float base = power(random);
    p.power = {base, base * 0.5f * (1 + unit(random)), base * 0.25f * (1 + unit(random))};
    p.bounce = static_cast<uint16_t>(i % 300);
    const StoredPhoton q = fromRecord(toRecord(p));
    EXPECT_EQ(q.position, p.position);
    EXPECT_GT(dot(q.direction, p.direction), 0.99999f);
    const float largest = maxComponent(p.power);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(q.power[c], p.power[c], largest / 128.0f) << c;
    EXPECT_EQ(q.bounce, std::min<uint16_t>(p.bounce, 255));
  }
}

TEST(PhotonRecord, UnpackFiltersDirectPhotonsAndRejectsTornTables) {
  std::vector<StoredPhoton> photons(3);
  for (int i = 0; i < 3; ++i) {
    photons[i].position = Vec3(float(i));
    photons[i].direction = {0, -1, 0};
    photons[i].power = Vec3(1);
    photons[i].bounce = static_cast<uint16_t>(i);
  }
  const std::string bytes = packRecords(photons);
  ASSERT_EQ(bytes.size(), 3 * sizeof(PhotonRecord));
  std::vector<StoredPhoton> all, indirect;
  unpackRecords(bytes.data(), bytes.size(), true, all);
  unpackRecords(bytes.data(), bytes.size(), false, indirect);
  EXPECT_EQ(all.size(), 3u);
  EXPECT_EQ(indirect.size(), 2u);
  EXPECT_THROW(unpackRecords(bytes.data(), bytes.size() - 1, true, all), std::runtime_error);
}

TEST(PhotonRecord, ZeroAndTinyPowersStayFinite) {
  EXPECT_EQ(decodeRgbe(encodeRgbe(Vec3(0))), Vec3(0));
  const Vec3 tiny = decodeRgbe(encodeRgbe(Vec3(1e-30f, 0, 0)));
  EXPECT_TRUE(isFinite(tiny));
}

}  // namespace
}  // namespace portico
