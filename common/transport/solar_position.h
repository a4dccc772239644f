// The sun's position in the sky of a place on the Earth at a UTC instant,
// by IAU SOFA's routines as ERFA (Debian's liberfa): the Earth's
// heliocentric position (eraEpv00, VSOP2000-fitted), then the standard
// reduction to observed place (eraAtco13: aberration, precession-nutation,
// Earth rotation, polar motion and UT1 - UTC taken as 0), and the sun's
// diurnal parallax. No atmospheric refraction: the elevation is the
// geometric one, as NREL's SPA reports it without refraction (the apparent
// sun is higher by under 0.1 degrees above 10 degrees of elevation, about
// half a degree at the horizon). Within 0.01 degrees of NREL's SPA in the
// tests (tests/unit/transport/solar_position_test.cpp).
#pragma once

#include <cstdint>

namespace portico {

struct SolarPosition {
  // Geographic azimuth: degrees clockwise from north seen from above
  // (90 = east), 0 to 360.
  double azimuthDegrees = 0;
  double elevationDegrees = 0;   // above the horizontal, -90 to 90
};

// The earliest and latest years solarPosition computes (those of eraEpv00's
// fit).
constexpr int kSolarPositionFirstYear = 1900, kSolarPositionLastYear = 2100;

// The sun seen from latitude/longitude (degrees, north and east positive)
// at `unixSeconds` (seconds since 1970-01-01T00:00Z, leap seconds not
// counted, as POSIX time). Throws std::invalid_argument for a latitude or
// longitude out of range or an instant outside kSolarPosition*Year.
SolarPosition solarPosition(int64_t unixSeconds, double latitudeDegrees, double longitudeDegrees);

}  // namespace portico
