// Writes sensors as a Radiance points file (.pts): one `x y z dx dy dz`
// line per sensor, in order, so a grid placed by `--grid auto` can be given
// again with `--sensors` or to Radiance's `rtrace -I`.
#pragma once

#include <string>
#include <vector>

#include "common/analysis/sensor.h"

namespace portico {

// The file's text: each number in the shortest form that reads back to the
// same float, so writing and reading again gives the same sensors.
std::string ptsText(const std::vector<Sensor>& sensors);

// Writes ptsText(sensors) to `path` atomically (never half-written).
// Throws std::runtime_error naming the path when it cannot be written.
void writePtsFile(const std::string& path, const std::vector<Sensor>& sensors);

}  // namespace portico
