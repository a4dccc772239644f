#include "common/scene/store/site_location.h"

#include <fmt/format.h>

#include <cmath>

namespace portico {

namespace {
std::string rangeProblem(double degrees, double most) {
  if (std::isfinite(degrees) && degrees >= -most && degrees <= most) return "";
  return fmt::format("must be a number of degrees from {:g} to {:g}", -most, most);
}
}  // namespace

std::string latitudeProblem(double degrees) { return rangeProblem(degrees, 90); }
std::string longitudeProblem(double degrees) { return rangeProblem(degrees, 180); }
std::string northAzimuthProblem(double degrees) { return rangeProblem(degrees, 360); }

std::string siteLocationProblem(const SiteLocation& site) {
  const struct {
    const char* name;
    double value;
    std::string problem;
  } values[] = {{"latitude", site.latitudeDegrees, latitudeProblem(site.latitudeDegrees)},
                {"longitude", site.longitudeDegrees, longitudeProblem(site.longitudeDegrees)},
                {"north azimuth", site.northAzimuthDegrees, northAzimuthProblem(site.northAzimuthDegrees)}};
  for (const auto& value : values)
    if (!value.problem.empty()) return fmt::format("{} {} {}", value.name, value.value, value.problem);
  return "";
}

}  // namespace portico
