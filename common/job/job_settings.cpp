#include "common/job/job_settings.h"

namespace portico {

std::string cameraChoiceProblem(const JobSettings& settings) {
  if (settings.cameraName.empty() || !settings.camera) return {};
  return "--camera '" + settings.cameraName +
         "' and --look-from both choose the job's camera: give one of them (--camera for a camera of the store)";
}

const char* toString(JobSettings::Irradiance irradiance) {
  return irradiance == JobSettings::Irradiance::Knn ? "knn" : "precomputed";
}

const char* toString(JobSettings::Aov aov) {
  switch (aov) {
    case JobSettings::Aov::Cells: return "cells";
    case JobSettings::Aov::Portals: return "portals";
    default: return "radiance";
  }
}

}  // namespace portico
