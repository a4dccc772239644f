// The scale of `portico bench paper`: what each mode (default, --quick, the
// ctest's --smoke) runs. The paper shot 50 000 photons per light on a 2006
// dual Xeon; here the counts are cut so that the default finishes in under
// an hour and --quick in a few minutes on a 2-core machine.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "coordinator/cli/bench/bench_paper.h"

namespace portico::cli::paper {

struct Scale {
  std::string mode;
  std::vector<std::string> buildings;   // Fig. 5, Table 3, Figs. 7-9, auto_vs_fixed
  std::string floorBuilding;            // Figs. 4 and 6 ("one floor of Tower101")
  bool floorInComparisons = false;      // the floor also in Figs. 7-9 and auto_vs_fixed
  std::vector<int> gridResolutions;
  int hgridResolution = 64;             // Fig. 6: the paper's 64^3 top grid
  std::vector<int> hgridMax;
  uint64_t photonsPerLight = 0, fewPhotonsPerLight = 0;
  std::map<std::string, std::vector<uint32_t>> uniformGrids;   // Table 4: building -> RG values
  uint32_t renderWidth = 0, renderHeight = 0, renderGather = 4;
  std::string renderAccel = "kd:sah";   // the paper's best structure for final gathering
  double timeoutSeconds = 600;
};

// The mode's scale with the options' overrides (photons per light, timeout,
// buildings); throws std::invalid_argument naming an unknown building.
Scale chooseScale(const BenchPaperOptions& options);

// The buildings of the comparisons (Figs. 7-9, auto_vs_fixed): the mode's
// buildings, plus the floor where it is compared too.
std::vector<std::string> comparedBuildings(const Scale& scale);

// "a,b,,c" -> {"a", "b", "c"}.
std::vector<std::string> splitList(const std::string& text);

// What the run does, for stdout and OUT/README.txt, and for summary.json.
std::string scaleHeader(const BenchPaperOptions& options, const Scale& scale);
nlohmann::json scaleJson(const BenchPaperOptions& options, const Scale& scale);

}  // namespace portico::cli::paper
