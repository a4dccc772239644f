// Reads images as linear RGB floats, through OpenImageIO (for tests and
// comparisons; the services never read images).
#pragma once

#include <string>

#include "common/image/linear_image.h"

namespace portico {

// Any format OpenImageIO reads; throws std::runtime_error naming the path.
LinearImage readImage(const std::string& path);

}  // namespace portico
