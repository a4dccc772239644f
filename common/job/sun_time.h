// A sun by date, time and place (`--sun-time`, docs/daylight.md): the
// instant as ISO 8601 with its UTC offset, and the sun's direction it gives
// in portico's convention.
//
// portico's coordinates are right-handed (a camera's right is forward x
// up, common/transport/camera_model.h) with +Y up, and its azimuths turn
// from +Z towards +X. Seen from above, +Z to +X turns anticlockwise, while
// a geographic azimuth turns clockwise (north, then east): with geographic
// north at portico azimuth N, geographic azimuth A is portico azimuth
// N - A. With N = 0 (+Z north), east is -X (azimuth 270) and west is +X.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "common/job/job_settings.h"
#include "common/scene/store/site_location.h"

namespace portico {

// "YYYY-MM-DDTHH:MM[:SS]" with its offset from UTC: "Z", "+HH:MM",
// "-HH:MM", "+HHMM" or "+HH" (a space may stand for the T). Returns POSIX
// seconds; throws std::invalid_argument with what is wrong (a time without
// an offset is refused: it would mean a different instant in every zone).
int64_t parseIsoInstant(std::string_view text);
// "2026-06-21T12:30:00Z".
std::string formatUtcInstant(int64_t unixSeconds);

// The portico azimuth, 0 to 360, of geographic azimuth `geographicDegrees`
// (clockwise from north) where geographic north is at portico azimuth
// `northAzimuthDegrees`.
double porticoAzimuth(double northAzimuthDegrees, double geographicDegrees);

// "" or the one-line problem with a sun time's own values, naming the option.
std::string sunTimeProblem(const SunTime& sunTime);

// The daylight's sun azimuth and elevation from its sunTime, at its place
// or else the store's `site` (north azimuth: the job's, else the site's,
// else 0), and sunTime cleared. Daylight without a sun time comes back as
// it was. Throws std::invalid_argument in one line when there is no place
// (no --latitude/--longitude and no site) or the sun is below the horizon
// then (naming its elevation).
DaylightSettings resolveSunTime(DaylightSettings daylight, const std::optional<SiteLocation>& site,
                                const std::string& storeDirectory);

}  // namespace portico
