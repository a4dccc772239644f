#include "common/job/sun_time.h"

#include <fmt/format.h>

#include <charconv>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "common/transport/solar_position.h"

namespace portico {

namespace {

// Reads exactly `digits` decimal digits at `at`; nullopt otherwise.
std::optional<int> digitsAt(std::string_view text, size_t at, size_t digits) {
  if (at + digits > text.size()) return std::nullopt;
  int value = 0;
  for (size_t k = at; k < at + digits; ++k) {
    if (text[k] < '0' || text[k] > '9') return std::nullopt;
    value = value * 10 + (text[k] - '0');
  }
  return value;
}

// The UTC offset in seconds of `zone` ("Z", "+HH:MM", "+HHMM", "+HH"),
// or nullopt.
std::optional<int> offsetSeconds(std::string_view zone) {
  if (zone == "Z" || zone == "z") return 0;
  if (zone.empty() || (zone[0] != '+' && zone[0] != '-')) return std::nullopt;
  const int sign = zone[0] == '-' ? -1 : 1;
  const auto hours = digitsAt(zone, 1, 2);
  std::optional<int> minutes = 0;
  if (zone.size() == 6 && zone[3] == ':') minutes = digitsAt(zone, 4, 2);
  else if (zone.size() == 5) minutes = digitsAt(zone, 3, 2);
  else if (zone.size() != 3) return std::nullopt;
  if (!hours || !minutes || *hours > 23 || *minutes > 59) return std::nullopt;
  return sign * (*hours * 3600 + *minutes * 60);
}

}  // namespace

int64_t parseIsoInstant(std::string_view text) {
  constexpr const char* kForm = "YYYY-MM-DDTHH:MM[:SS] and an offset (Z, +HH:MM or -HH:MM)";
  const auto fail = [&](const std::string& problem) -> int64_t {
    throw std::invalid_argument(fmt::format("'{}' {}", text, problem));
  };
  const auto year = digitsAt(text, 0, 4), month = digitsAt(text, 5, 2), day = digitsAt(text, 8, 2);
  const auto hour = digitsAt(text, 11, 2), minute = digitsAt(text, 14, 2);
  if (!year || !month || !day || !hour || !minute || text[4] != '-' || text[7] != '-' ||
      (text[10] != 'T' && text[10] != 't' && text[10] != ' ') || text[13] != ':')
    return fail(fmt::format("is not a date and time {}", kForm));
  size_t at = 16;
  int second = 0;
  if (at < text.size() && text[at] == ':') {
    const auto seconds = digitsAt(text, at + 1, 2);
    if (!seconds) return fail(fmt::format("is not a date and time {}", kForm));
    second = *seconds;
    at += 3;
  }
  if (at == text.size())
    return fail("has no UTC offset: add one (+02:00 for central European summer time, Z for UTC), as the same "
                "clock time is another instant in every time zone");
  const auto offset = offsetSeconds(text.substr(at));
  if (!offset) return fail(fmt::format("has no valid UTC offset after the time: {}", kForm));
  const std::chrono::year_month_day date{std::chrono::year(*year), std::chrono::month(unsigned(*month)),
                                        std::chrono::day(unsigned(*day))};
  if (!date.ok()) return fail(fmt::format("is no date: {:04}-{:02} has no day {}", *year, *month, *day));
  if (*hour > 23 || *minute > 59 || second > 59)
    return fail(fmt::format("is no time of day: {:02}:{:02}:{:02}", *hour, *minute, second));
  const int64_t days = std::chrono::sys_days(date).time_since_epoch().count();
  return days * 86400 + *hour * 3600 + *minute * 60 + second - *offset;
}

std::string formatUtcInstant(int64_t unixSeconds) {
  using namespace std::chrono;
  const sys_seconds instant{seconds(unixSeconds)};
  const sys_days day = floor<days>(instant);
  const year_month_day date{day};
  const int64_t secondOfDay = (instant - day).count();
  return fmt::format("{:04}-{:02}-{:02}T{:02}:{:02}:{:02}Z", int(date.year()), unsigned(date.month()),
                     unsigned(date.day()), secondOfDay / 3600, secondOfDay / 60 % 60, secondOfDay % 60);
}

double porticoAzimuth(double northAzimuthDegrees, double geographicDegrees) {
  const double azimuth = std::fmod(northAzimuthDegrees - geographicDegrees, 360.0);
  return azimuth < 0 ? azimuth + 360.0 : azimuth;
}

std::string sunTimeProblem(const SunTime& t) {
  const struct {
    const char* option;
    const std::optional<double>& value;
    std::string (*problem)(double);
  } values[] = {{"--latitude", t.latitudeDegrees, latitudeProblem},
                {"--longitude", t.longitudeDegrees, longitudeProblem},
                {"--north-azimuth", t.northAzimuthDegrees, northAzimuthProblem}};
  for (const auto& value : values)
    if (value.value)
      if (const std::string problem = value.problem(*value.value); !problem.empty())
        return fmt::format("{} {} {}", value.option, *value.value, problem);
  if (t.latitudeDegrees.has_value() != t.longitudeDegrees.has_value())
    return "--latitude and --longitude go together: give both, or neither for the store's site";
  return "";
}

DaylightSettings resolveSunTime(DaylightSettings daylight, const std::optional<SiteLocation>& site,
                                const std::string& storeDirectory) {
  if (!daylight.sunTime) return daylight;
  const SunTime& t = *daylight.sunTime;
  const std::string when = formatUtcInstant(t.unixSeconds);
  if (const std::string problem = sunTimeProblem(t); !problem.empty()) throw std::invalid_argument(problem);
  if (!t.latitudeDegrees && !site)
    throw std::invalid_argument(fmt::format("--sun-time {}: no place to see the sun from: give --latitude and "
                                            "--longitude (scene {} has no site)",
                                            when, storeDirectory));
  const double latitude = t.latitudeDegrees ? *t.latitudeDegrees : site->latitudeDegrees;
  const double longitude = t.longitudeDegrees ? *t.longitudeDegrees : site->longitudeDegrees;
  const double north = t.northAzimuthDegrees ? *t.northAzimuthDegrees : site ? site->northAzimuthDegrees : 0.0;
  SolarPosition sun;
  try {
    sun = solarPosition(t.unixSeconds, latitude, longitude);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(fmt::format("--sun-time {}: {}", when, e.what()));
  }
  if (!(sun.elevationDegrees > 0))
    throw std::invalid_argument(fmt::format(
        "--sun-time {}: the sun is below the horizon at latitude {}, longitude {} (elevation {:.2f} degrees); "
        "choose a time of day, or daylight without a sun (--sky overcast)",
        when, latitude, longitude, sun.elevationDegrees));
  daylight.sunAzimuthDegrees = static_cast<float>(porticoAzimuth(north, sun.azimuthDegrees));
  daylight.sunElevationDegrees = static_cast<float>(sun.elevationDegrees);
  daylight.sun = true;
  daylight.sunTime.reset();
  return daylight;
}

}  // namespace portico
