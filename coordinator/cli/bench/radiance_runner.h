// Radiance's programs (oconv, rtrace) run from `portico bench analyze`: the
// programs of PyPI's pyradiance in the sources' .venv (deploy/install-deps.sh),
// else Radiance on PATH; each run with its lib/ on RAYPATH (docs/radiance.md).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "common/math.h"

namespace portico::cli {

struct RadianceInstall {
  std::string bin;   // the folder of oconv, rtrace, ...
  std::string lib;   // the folder of skybright.cal, ... (for RAYPATH); may be ""
};

// nullopt when neither .venv's pyradiance nor an rtrace on PATH is found.
std::optional<RadianceInstall> findRadiance();

// Runs `argv` (argv[0] a Radiance program's name) with its standard input
// from `input` ("" for none) and its standard output into `output`; its
// messages go to `log`. Throws std::runtime_error with the log when it fails.
void runRadiance(const RadianceInstall& radiance, const std::vector<std::string>& argv, const std::string& input,
                 const std::string& output, const std::string& log);

// The irradiance R G B (W/m^2) of each line of `rtrace -h -I` output.
std::vector<Vec3> readRtraceIrradiance(const std::string& path);

}  // namespace portico::cli
