#include "common/job/job_settings.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <filesystem>

namespace portico {

std::string cameraChoiceProblem(const JobSettings& settings) {
  if (settings.cameraName.empty() || !settings.camera) return {};
  return "--camera '" + settings.cameraName +
         "' and --look-from both choose the job's camera: give one of them (--camera for a camera of the store)";
}

std::string luminanceProblem(const JobSettings& settings) {
  if (!settings.luminance) return {};
  const LuminanceImage& luminance = *settings.luminance;
  if (settings.analysis) return "--aov luminance and --falsecolor are for renders, not analyses";
  if (settings.aov != JobSettings::Aov::Radiance)
    return fmt::format("--aov luminance is the radiance render in cd/m^2, not --aov {}", toString(settings.aov));
  std::string extension = std::filesystem::path(settings.output).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) { return std::tolower(c); });
  if (extension != ".exr" && extension != ".hdr" && extension != ".tif" && extension != ".tiff")
    return fmt::format("output {}: --aov luminance writes cd/m^2 as floats: give a file name ending in .exr, .hdr or "
                       ".tif (--falsecolor writes its PNG beside it)",
                       settings.output);
  if (!(luminance.falseColorMaximum >= 0 && luminance.falseColorMaximum <= kMaxFalseColorMaximum))
    return fmt::format("--falsecolor-max {} must be a number of cd/m^2 above 0 and at most {:g}",
                       luminance.falseColorMaximum, kMaxFalseColorMaximum);
  if (luminance.falseColorDecades > kMaxFalseColorDecades)
    return fmt::format("--falsecolor-log {} must be 1 to {} decades", luminance.falseColorDecades,
                       kMaxFalseColorDecades);
  if (luminance.falseColorSteps < 1 || luminance.falseColorSteps > kMaxFalseColorSteps)
    return fmt::format("--falsecolor-steps {} must be 1 to {}", luminance.falseColorSteps, kMaxFalseColorSteps);
  return {};
}

const char* toString(JobSettings::Irradiance irradiance) {
  return irradiance == JobSettings::Irradiance::Knn ? "knn" : "precomputed";
}

const char* toString(LightSampling sampling) { return sampling == LightSampling::Scan ? "scan" : "tree"; }

const char* toString(JobSettings::Aov aov) {
  switch (aov) {
    case JobSettings::Aov::Cells: return "cells";
    case JobSettings::Aov::Portals: return "portals";
    default: return "radiance";
  }
}

}  // namespace portico
