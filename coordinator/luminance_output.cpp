#include "coordinator/luminance_output.h"

#include <filesystem>

#include "common/analysis/luminance_image.h"
#include "common/image/image_writer.h"
#include "coordinator/cli/false_color_image.h"

namespace portico {

nlohmann::json writeLuminanceOutputs(const std::string& output, const LinearImage& radiance,
                                     wire::LuminanceImage::Reader options) {
  const LinearImage luminance = luminanceImage(radiance);
  writeImage(output, luminance);
  nlohmann::json record = {{"unit", "cd/m2"}};
  if (!options.getFalseColor()) return record;
  FalseColorScale scale;
  scale.maximum = options.getFalseColorMaximum();   // 0: drawFalseColorImage chooses it
  scale.decades = int(options.getFalseColorDecades());
  scale.steps = int(options.getFalseColorSteps());
  scale.unit = "cd/m2";
  FalseColorScale drawn;
  const cli::Canvas canvas = cli::drawFalseColorImage(luminance, scale, &drawn);
  const std::filesystem::path path = cli::falseColorImagePath(output);
  const std::filesystem::path temporary = path.parent_path() / (".tmp-" + path.filename().string());
  cli::writePng(temporary.string(), canvas, "false-colour picture");
  std::filesystem::rename(temporary, path);
  record["falsecolor"] = {{"path", path.string()},
                          {"maximum", drawn.maximum},
                          {"scale", drawn.decades > 0 ? "log" : "linear"},
                          {"decades", drawn.decades},
                          {"steps", drawn.steps}};
  return record;
}

}  // namespace portico
