// A luminance job's outputs (--aov luminance, --falsecolor;
// common/job/job_settings.h LuminanceImage): the render's radiance as
// cd/m^2 in a float image at the job's output, and its false-colour picture
// with a legend beside it (OUTPUT.falsecolor.png).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "common/image/linear_image.h"
#include "proto/wire.capnp.h"

namespace portico {

// Writes both (each written beside its name and renamed); returns what the
// job's statistics record of them: the false-colour picture's path and the
// scale drawn (its top chosen here when the job gave none).
nlohmann::json writeLuminanceOutputs(const std::string& output, const LinearImage& radiance,
                                     wire::LuminanceImage::Reader options);

}  // namespace portico
