// OpenEXR files of linear RGB floats, through the OpenEXR library itself:
// a dozen shared libraries where OpenImageIO loads ~300, which a process
// pays for at every start (the coordinator writes every job's image).
#pragma once

#include <string>

#include "common/image/linear_image.h"

namespace portico {

// Writes three FLOAT channels R, G, B with ZIP compression. Throws
// std::runtime_error naming the path on failure.
void writeExr(const std::string& path, const LinearImage& image);

}  // namespace portico
