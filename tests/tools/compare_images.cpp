// portico-compare IMAGE REFERENCE [--json] [--no-flip]: the reference
// scenes' comparison (image mean, 16x16 block means) and the per-pixel
// measures beside it (relative MSE, NVIDIA's FLIP where flip-evaluator is
// installed) printed as one line, or JSON with --json. Exits 0 when the
// image is within the reference tolerances (mean 3 %, blocks 10 %), 1 when
// not, 2 on an error.
#include <nlohmann/json.hpp>

#include <cstring>
#include <iostream>
#include <string>

#include "common/image/flip_error.h"
#include "common/image/image_compare.h"
#include "common/image/image_reader.h"

int main(int argc, char** argv) {
  bool json = false, flip = true;
  for (int i = 3; i < argc; ++i) {
    if (std::strcmp(argv[i], "--json") == 0) json = true;
    else if (std::strcmp(argv[i], "--no-flip") == 0) flip = false;
    else {
      std::cerr << "portico-compare: unknown option " << argv[i] << " (known: --json, --no-flip)\n";
      return 2;
    }
  }
  if (argc < 3) {
    std::cerr << "usage: portico-compare IMAGE REFERENCE [--json] [--no-flip]\n";
    return 2;
  }
  try {
    const auto comparison = portico::compareImages(portico::readImage(argv[1]), portico::readImage(argv[2]));
    const portico::FlipResult flipResult =
        flip ? portico::flipError(argv[1], argv[2]) : portico::FlipResult{std::nullopt, "--no-flip"};
    if (json) {
      nlohmann::json j{{"image_mean", comparison.imageMean},
                       {"reference_mean", comparison.referenceMean},
                       {"mean_relative_error", comparison.meanRelativeError},
                       {"blocks_checked", comparison.blocksChecked},
                       {"blocks_over_limit", comparison.blocksOverLimit},
                       {"worst_block_error", comparison.worstBlockError},
                       {"block_rmse", comparison.blockRmse},
                       {"relative_mse", comparison.relativeMse},
                       {"relative_mse_epsilon", portico::kRelativeMseEpsilon}};
      if (flipResult.mean) j["flip"] = *flipResult.mean;
      else j["flip_skipped"] = flipResult.skipped;
      for (const auto& b : comparison.blocks)
        if (b.checked && b.relativeError > 0.05)
          j["blocks_over_5_percent"].push_back({{"x", b.x}, {"y", b.y}, {"image", b.image},
                                                {"reference", b.reference}, {"error", b.relativeError}});
      std::cout << j.dump() << "\n";
    } else {
      std::cout << portico::describe(comparison)
                << (flipResult.mean ? "; FLIP " + std::to_string(*flipResult.mean)
                                    : "; FLIP skipped: " + flipResult.skipped)
                << "\n";
    }
    return comparison.meanRelativeError <= 0.03 && comparison.blocksOverLimit == 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "portico-compare: " << e.what() << "\n";
    return 2;
  }
}
