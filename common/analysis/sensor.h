// Lighting analysis: what a sensor is and what it reads. A sensor is a
// point and the direction its measuring plane faces (Radiance's .pts
// convention: `x y z dx dy dz`); it reads the illuminance on that plane
// from the whole hemisphere the direction points into. Shared by the
// sensor sources (a .pts file, the automatic work-plane grid), the
// analyze job, and the reports written from its readings.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/math.h"

namespace portico {

// Luminous efficacy that turns portico's radiometric units into
// photometric ones (docs/daylight.md): lux = 179 lm/W x Y, with Y the
// Rec. 709 luminance of the RGB irradiance in W/m^2.
constexpr double kLuminousEfficacy = 179.0;
inline double rec709Y(const Vec3& rgb) { return 0.2126 * rgb.x + 0.7152 * rgb.y + 0.0722 * rgb.z; }
inline double luxOf(const Vec3& irradianceRgb) { return kLuminousEfficacy * rec709Y(irradianceRgb); }

struct Sensor {
  Vec3 position;                     // metres, scene coordinates
  Vec3 direction;                    // unit normal of the measuring plane
  uint32_t sourceLine = 0;           // 1-based line of its .pts file; 0 when placed by --grid auto
  int64_t cell = -1;                 // the cell containing the position; -1: none (outside every cell)
  std::string room;                  // the cell's room name ("" when it has none)
};

struct SensorReading {
  Vec3 irradiance;                   // W/m^2 per RGB channel on the sensor's plane
  double lux = 0;                    // luxOf(irradiance)
  double standardError = 0;          // of lux, from the spread of the sensor's samples
  double directShare = 0;            // share of lux from direct light (lamps, sun, sky seen directly)
};

}  // namespace portico
