#include "common/job/job_settings.h"

namespace portico {

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
