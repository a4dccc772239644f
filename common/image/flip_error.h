// NVIDIA's FLIP (a perceptual per-pixel difference, mean over the image)
// of an image file against a reference file, by python/portico_quality/flip.py
// in the sources' .venv (flip-evaluator from PyPI, deploy/install-deps.sh):
// there is no C++ FLIP in Debian, and the PyPI package is NVIDIA's own code.
#pragma once

#include <optional>
#include <string>

namespace portico {

struct FlipResult {
  std::optional<double> mean;   // set when FLIP ran
  std::string skipped;          // otherwise: why not (no interpreter, no flip-evaluator, ...)
};

// $PORTICO_PYTHON, else the sources' .venv/bin/python3, runs the module.
FlipResult flipError(const std::string& image, const std::string& reference);

}  // namespace portico
