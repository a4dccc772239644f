// Where a building stands on the Earth (building.json "site", scene.db
// table site): what a sun by date and time (`--sun-time`) needs besides the
// time.
#pragma once

#include <string>

namespace portico {

struct SiteLocation {
  double latitudeDegrees = 0;       // north positive, -90 to 90
  double longitudeDegrees = 0;      // east positive, -180 to 180
  // The azimuth, in portico's convention (from +Z towards +X, +Y up), of
  // geographic north: 0 when +Z points north (docs/daylight.md).
  double northAzimuthDegrees = 0;
  bool operator==(const SiteLocation&) const = default;
};

// "" when `degrees` is a latitude (a finite number from -90 to 90), a
// longitude (-180 to 180) or a north azimuth (-360 to 360); else what it
// must be, to follow the name of the value at fault ("must be a number of
// degrees from -90 to 90").
std::string latitudeProblem(double degrees);
std::string longitudeProblem(double degrees);
std::string northAzimuthProblem(double degrees);

// The first problem of a whole location, naming its value
// ("latitude 95 must be ..."), or "".
std::string siteLocationProblem(const SiteLocation& site);

}  // namespace portico
