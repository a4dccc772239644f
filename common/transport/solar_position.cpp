#include "common/transport/solar_position.h"

#include <erfa.h>
#include <erfam.h>
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <stdexcept>

#include "common/scene/store/site_location.h"

namespace portico {

namespace {
constexpr double kUnixEpochJulianDate = 2440587.5;
constexpr double kSecondsPerDay = 86400.0;
constexpr double kEarthEquatorialRadiusMetres = 6378137.0;   // WGS84
constexpr double kAstronomicalUnitMetres = 149597870700.0;

// The instant's calendar year (proleptic Gregorian, UTC).
int yearOf(int64_t unixSeconds) {
  using namespace std::chrono;
  return int(year_month_day{floor<days>(sys_seconds{seconds(unixSeconds)})}.year());
}
}  // namespace

SolarPosition solarPosition(int64_t unixSeconds, double latitudeDegrees, double longitudeDegrees) {
  if (const std::string problem = latitudeProblem(latitudeDegrees); !problem.empty())
    throw std::invalid_argument(fmt::format("latitude {} {}", latitudeDegrees, problem));
  if (const std::string problem = longitudeProblem(longitudeDegrees); !problem.empty())
    throw std::invalid_argument(fmt::format("longitude {} {}", longitudeDegrees, problem));
  const int year = yearOf(unixSeconds);
  if (year < kSolarPositionFirstYear || year > kSolarPositionLastYear)
    throw std::invalid_argument(fmt::format("the year {} is outside {} to {}, the years the sun's position is computed for",
                                            year, kSolarPositionFirstYear, kSolarPositionLastYear));

  // UTC as a two-part quasi Julian date, as ERFA takes it: POSIX time
  // counts every day as 86 400 s, as ERFA's UTC day fraction does.
  const double days = std::floor(double(unixSeconds) / kSecondsPerDay);
  const double utc1 = kUnixEpochJulianDate + days;
  const double utc2 = (double(unixSeconds) - days * kSecondsPerDay) / kSecondsPerDay;
  double tai1 = 0, tai2 = 0, tt1 = 0, tt2 = 0;
  if (eraUtctai(utc1, utc2, &tai1, &tai2) < 0 || eraTaitt(tai1, tai2, &tt1, &tt2) != 0)
    throw std::invalid_argument(fmt::format("the instant {} s after 1970 cannot be converted to TT", unixSeconds));

  // The sun's direction from the geocentre: minus the Earth's heliocentric
  // position (the sun's own motion over the light time is under 0.01").
  double heliocentric[2][3], barycentric[2][3];
  eraEpv00(tt1, tt2, heliocentric, barycentric);
  double towardsSun[3];
  for (int k = 0; k < 3; ++k) towardsSun[k] = -heliocentric[0][k];
  const double distanceAu = eraPm(towardsSun);
  double rightAscension = 0, declination = 0;
  eraC2s(towardsSun, &rightAscension, &declination);

  // Observed place: pressure 0 turns refraction off.
  double azimuth = 0, zenithDistance = 0, hourAngle = 0, observedDeclination = 0, observedRa = 0, originEquation = 0;
  if (eraAtco13(eraAnp(rightAscension), declination, 0, 0, 0, 0, utc1, utc2, /*dut1=*/0,
                longitudeDegrees * ERFA_DD2R, latitudeDegrees * ERFA_DD2R, /*hm=*/0, /*xp=*/0, /*yp=*/0,
                /*phpa=*/0, /*tc=*/0, /*rh=*/0, /*wl=*/0, &azimuth, &zenithDistance, &hourAngle,
                &observedDeclination, &observedRa, &originEquation) < 0)
    throw std::invalid_argument(fmt::format("the instant {} s after 1970 is outside ERFA's dates", unixSeconds));

  // Diurnal parallax: seen from the surface rather than the geocentre, the
  // sun is lower by its horizontal parallax (8.8") times cos(elevation).
  const double geocentricElevation = ERFA_DPI / 2 - zenithDistance;
  const double sinParallax = kEarthEquatorialRadiusMetres / (distanceAu * kAstronomicalUnitMetres);
  const double elevation = geocentricElevation - std::asin(sinParallax * std::cos(geocentricElevation));
  return {eraAnp(azimuth) * ERFA_DR2D, elevation * ERFA_DR2D};
}

}  // namespace portico
