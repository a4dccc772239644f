// The floor plans the dashboard draws (as SVG, in the page) under a job's
// cell states: per floor, the footprint of each cell `portico scene plan`
// draws and its walls cut at eye height (coordinator/cli/scene_plan.h,
// plan_walls.h), in metres, x to the right and z downwards.
#pragma once

#include <nlohmann/json.hpp>

#include <string>

namespace portico::cli {

// {"floors": [{"floor", "level", "cells": [[id, x0, z0, x1, z1], ...],
// "walls": [[x0, z0, x1, z1], ...]}], "bounds": [x0, z0, x1, z1]}.
// Throws std::runtime_error naming the store when it cannot be read here.
nlohmann::json planGeometry(const std::string& storeDirectory);

}  // namespace portico::cli
