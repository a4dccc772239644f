// Radiance's sensor files (.pts, as rtrace -I and Honeybee read them): one
// sensor a line, `x y z dx dy dz`, numbers separated by blanks or tabs (or
// commas). Blank lines and lines starting with '#' are skipped. The
// direction need not be of unit length (it is normalised) but must not be
// zero.
#pragma once

#include <string>
#include <vector>

#include "common/analysis/sensor.h"

namespace portico {

// The sensors of `path` in its order, each with its 1-based line
// (Sensor::sourceLine; cell and room left unset). Throws
// std::invalid_argument "PATH:LINE: problem" for a line that is not six
// finite numbers or whose direction is zero, and naming the file when it
// cannot be read or holds no sensor.
std::vector<Sensor> readPtsFile(const std::string& path);

}  // namespace portico
