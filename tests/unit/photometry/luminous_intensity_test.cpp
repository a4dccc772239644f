// The sphere's candela distribution read from IES files of every symmetry:
// its total lumens against the closed-form integral of the function the
// file samples, its intensity in given directions, and the directions it
// draws against the distribution.
#include "common/photometry/luminous_intensity.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "common/photometry/ies_file.h"
#include "common/rng.h"
#include "tests/unit/photometry/ies_test_files.h"

namespace portico {
namespace {

using ies_test::angles;
using ies_test::iesText;

constexpr double kDeg = M_PI / 180.0;
using Candela = std::function<double(double, double)>;   // (gamma, c) in degrees

LuminousIntensity fromFile(const std::vector<double>& vertical, const std::vector<double>& horizontal,
                           const Candela& candela) {
  return LuminousIntensity(parseIes(iesText(vertical, horizontal, candela), "test.ies").grid, "test.ies");
}

// The direction (gamma, c) in the luminaire's frame.
Vec3 direction(double gamma, double c) {
  return Vec3(float(std::sin(gamma * kDeg) * std::cos(c * kDeg)), float(std::sin(gamma * kDeg) * std::sin(c * kDeg)),
              float(std::cos(gamma * kDeg)));
}

struct Case {
  const char* name;
  std::vector<double> vertical, horizontal;
  Candela candela;     // what the file samples, over its own angles
  Candela everywhere;  // the same function over the whole sphere (the symmetry unfolded)
  double lumens;       // its closed-form integral over the sphere
};

std::vector<Case> cases() {
  const double a = 1000, b = 400;
  return {
      // Isotropic 1000 cd: 4 pi 1000 lm.
      {"isotropic", angles(0, 180, 5), {0}, [](double, double) { return 1000.0; },
       [](double, double) { return 1000.0; }, 4 * M_PI * 1000},
      // Lambertian downlight I0 cos(gamma), I0 = 1000: pi I0.
      {"cosine", angles(0, 90, 2.5), {0}, [](double g, double) { return 1000 * std::cos(g * kDeg); },
       [](double g, double) { return g <= 90 ? 1000 * std::cos(g * kDeg) : 0.0; }, M_PI * 1000},
      // Uplight, 90-180 only: 2 pi I0.
      {"uplight", angles(90, 180, 10), {0}, [](double, double) { return 500.0; },
       [](double g, double) { return g >= 90 ? 500.0 : 0.0; }, 2 * M_PI * 500},
      // Quadrant symmetry (0-90): a + b cos^2 C -> 4 pi a + 2 pi b.
      {"quadrants", angles(0, 180, 5), angles(0, 90, 5),
       [=](double, double c) { return a + b * std::pow(std::cos(c * kDeg), 2); },
       [=](double, double c) { return a + b * std::pow(std::cos(c * kDeg), 2); }, 4 * M_PI * a + 2 * M_PI * b},
      // Bilateral (0-180), mirrored across C0-C180: a + b |sin C| -> 4 pi a + 8 b.
      {"bilateral", angles(0, 180, 5), angles(0, 180, 5),
       [=](double, double c) { return a + b * std::abs(std::sin(c * kDeg)); },
       [=](double, double c) { return a + b * std::abs(std::sin(c * kDeg)); }, 4 * M_PI * a + 8 * b},
      // Bilateral (90-270), mirrored across C90-C270: a + b sin(gamma) |cos C|
      // -> 4 pi a + b (pi / 2) 4 (the integral of sin^2 gamma is pi / 2, of |cos C| 4).
      {"bilateral 90-270", angles(0, 180, 5), angles(90, 270, 5),
       [=](double g, double c) { return a + b * std::sin(g * kDeg) * (-std::cos(c * kDeg)); },
       [=](double g, double c) { return a + b * std::sin(g * kDeg) * std::abs(std::cos(c * kDeg)); },
       4 * M_PI * a + b * (M_PI / 2) * 4},
      // Full 0-360, downward only: a (1 + 0.5 cos C) cos gamma -> pi a.
      {"full circle", angles(0, 90, 2.5), angles(0, 360, 5),
       [=](double g, double c) { return a * (1 + 0.5 * std::cos(c * kDeg)) * std::cos(g * kDeg); },
       [=](double g, double c) { return g <= 90 ? a * (1 + 0.5 * std::cos(c * kDeg)) * std::cos(g * kDeg) : 0.0; },
       M_PI * a},
  };
}

// The sum of candela x solid angle over the sphere against the closed form:
// within 0.1 % (the file samples the function every 2.5-10 degrees and is
// read linearly between; the 0.5 x 1 degree cells add less than that).
TEST(LuminousIntensity, TotalLumensMatchTheClosedFormForEverySymmetry) {
  for (const Case& c : cases()) {
    const LuminousIntensity intensity = fromFile(c.vertical, c.horizontal, c.candela);
    const double error = intensity.lumens() / c.lumens - 1;
    std::printf("  %-18s %10.2f lm, closed form %10.2f lm, error %+.4f %%\n", c.name, intensity.lumens(), c.lumens,
                100 * error);
    EXPECT_NEAR(error, 0.0, 1e-3) << c.name;
  }
}

// The intensity towards directions all round (the symmetry unfolded) is the
// function's, to within what the grid and the cells leave (15 cd of up to 1500).
TEST(LuminousIntensity, IntensityInEveryDirectionUnfoldsTheSymmetry) {
  for (const Case& c : cases()) {
    const LuminousIntensity intensity = fromFile(c.vertical, c.horizontal, c.candela);
    for (double gamma = 1.1; gamma < 180; gamma += 7.3)
      for (double az = 3.2; az < 360; az += 11.7) {
        const double expected = c.everywhere(gamma, az);
        // Next to a cut-off (a half-space file's edge at 90 degrees) the cell straddles it.
        if (std::abs(gamma - 90) < 1) continue;
        EXPECT_NEAR(intensity.candela(direction(gamma, az)), expected, 15 + 2e-3 * expected)
            << c.name << " at gamma " << gamma << ", C " << az;
      }
  }
}

TEST(LuminousIntensity, AFileOfOnePlaneIsTheSameAllAround) {
  const LuminousIntensity intensity =
      fromFile(angles(0, 90, 5), {0}, [](double g, double) { return 100 + g; });
  for (double az : {0.0, 77.0, 181.0, 359.0})
    EXPECT_FLOAT_EQ(intensity.candela(direction(30.2, az)), intensity.candela(direction(30.2, 0)));
}

// Directions drawn by sample() fall into zones of the sphere (every 15
// degrees of gamma and 45 of C) as often as the zone's share of the
// closed-form flux says: within 4 standard deviations, and within 0.5 % of
// the flux where a zone holds much.
TEST(LuminousIntensity, SampledDirectionsFollowTheDistribution) {
  for (const Case& c : cases()) {
    const LuminousIntensity intensity = fromFile(c.vertical, c.horizontal, c.candela);
    constexpr int kRows = 12, kColumns = 8, kDraws = 400000;
    std::vector<double> counts(kRows * kColumns, 0.0);
    for (uint64_t n = 0; n < kDraws; ++n) {
      const Vec3 d = intensity.sample(randomUniform(5, RandomStream::Photon, n, 0, 0),
                                      randomUniform(5, RandomStream::Photon, n, 0, 1),
                                      randomUniform(5, RandomStream::Photon, n, 0, 2),
                                      randomUniform(5, RandomStream::Photon, n, 0, 3));
      ASSERT_NEAR(length(d), 1.0f, 1e-5f);
      double az = std::atan2(d.y, d.x) / kDeg;
      if (az < 0) az += 360;
      const int row = std::min(kRows - 1, int(std::acos(std::clamp(double(d.z), -1.0, 1.0)) / kDeg / 15));
      const int column = std::min(kColumns - 1, int(az / 45));
      counts[row * kColumns + column] += 1;
    }
    // Each zone's flux by the midpoint rule on a fine grid of the closed-form function.
    for (int row = 0; row < kRows; ++row)
      for (int column = 0; column < kColumns; ++column) {
        double flux = 0;
        constexpr int kSteps = 90;
        for (int i = 0; i < kSteps; ++i)
          for (int j = 0; j < kSteps; ++j) {
            const double g0 = row * 15 + 15.0 * i / kSteps, g1 = g0 + 15.0 / kSteps;
            const double az = column * 45 + 45.0 * (j + 0.5) / kSteps;
            flux += c.everywhere(0.5 * (g0 + g1), az) * (std::cos(g0 * kDeg) - std::cos(g1 * kDeg)) *
                    (45.0 / kSteps * kDeg);
          }
        const double p = flux / c.lumens;
        const double expected = p * kDraws, sigma = std::sqrt(kDraws * p * (1 - p));
        EXPECT_NEAR(counts[row * kColumns + column], expected, 4 * sigma + 2e-3 * kDraws * p + 1)
            << c.name << " zone gamma " << row * 15 << ", C " << column * 45;
      }
  }
}

}  // namespace
}  // namespace portico
