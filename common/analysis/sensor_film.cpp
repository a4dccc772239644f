#include "common/analysis/sensor_film.h"

#include <cmath>

namespace portico {

namespace {
Vec3 irradianceOf(const FixedRgb& sum) {
  const auto value = [](int64_t v) { return static_cast<float>(static_cast<double>(v) / kFilmScale); };
  return Vec3(value(sum.r), value(sum.g), value(sum.b));
}
}  // namespace

SensorReading sensorReading(const std::vector<FixedRgb>& film, uint32_t sensor, uint32_t spp) {
  const uint32_t groups = sensorGroups(spp);
  SensorReading reading;
  Vec3 direct;
  // Each group's columns hold its estimate divided by `groups`.
  std::vector<double> groupLux(groups);
  for (uint32_t g = 0; g < groups; ++g) {
    const Vec3 groupDirect = irradianceOf(film.at(directSlot(sensor, g)));
    const Vec3 groupIndirect = irradianceOf(film.at(indirectSlot(sensor, g)));
    direct += groupDirect;
    reading.irradiance += groupDirect + groupIndirect;
    groupLux[g] = luxOf(groupDirect + groupIndirect) * groups;
  }
  reading.lux = luxOf(reading.irradiance);
  if (groups > 1) {
    double squares = 0;
    for (double lux : groupLux) squares += (lux - reading.lux) * (lux - reading.lux);
    reading.standardError = std::sqrt(squares / (double(groups) * (groups - 1)));
  }
  reading.directShare = reading.lux > 0 ? luxOf(direct) / reading.lux : 0.0;
  return reading;
}

}  // namespace portico
