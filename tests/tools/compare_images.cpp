// portico-compare IMAGE REFERENCE: the reference scenes' comparison (image
// mean, 16x16 block means) printed as one line, or JSON with --json.
#include <nlohmann/json.hpp>

#include <cstring>
#include <iostream>

#include "common/image/image_compare.h"
#include "common/image/image_reader.h"

int main(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: portico-compare IMAGE REFERENCE [--json]\n";
    return 2;
  }
  try {
    const auto comparison = portico::compareImages(portico::readImage(argv[1]), portico::readImage(argv[2]));
    if (argc > 3 && std::strcmp(argv[3], "--json") == 0) {
      nlohmann::json j{{"image_mean", comparison.imageMean},
                       {"reference_mean", comparison.referenceMean},
                       {"mean_relative_error", comparison.meanRelativeError},
                       {"blocks_checked", comparison.blocksChecked},
                       {"blocks_over_limit", comparison.blocksOverLimit},
                       {"worst_block_error", comparison.worstBlockError}};
      for (const auto& b : comparison.blocks)
        if (b.checked && b.relativeError > 0.05)
          j["blocks_over_5_percent"].push_back({{"x", b.x}, {"y", b.y}, {"image", b.image},
                                                {"reference", b.reference}, {"error", b.relativeError}});
      std::cout << j.dump() << "\n";
    } else {
      std::cout << portico::describe(comparison) << "\n";
    }
    return comparison.meanRelativeError <= 0.03 && comparison.blocksOverLimit == 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "portico-compare: " << e.what() << "\n";
    return 2;
  }
}
