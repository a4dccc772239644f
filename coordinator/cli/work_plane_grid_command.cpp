#include "coordinator/cli/work_plane_grid_command.h"

#include <fmt/format.h>

#include <iostream>
#include <map>

#include "common/analysis/pts_file_writer.h"
#include "common/scene/store/floor_levels.h"

namespace portico::cli {

std::vector<CLI::Option*> addWorkPlaneGridOptions(CLI::App& command, WorkPlaneGridOptions& o) {
  return {
      command.add_option("--grid-height", o.height, "work plane: metres above each room's floor")
          ->capture_default_str()
          ->check(CLI::Range(0.01, 100.0)),
      command.add_option("--grid-spacing", o.spacing, "metres between grid points (LEED asks at most 0.6)")
          ->capture_default_str()
          ->check(CLI::Range(0.01, 100.0)),
      command.add_option("--grid-inset", o.inset, "metres kept from walls and the floor's edges")
          ->capture_default_str()
          ->check(CLI::Range(0.0, 100.0)),
      command.add_option("--grid-rooms", o.roomNames, "only cells whose names match one of these patterns (f0-room-*)")
          ->delimiter(','),
      command.add_option("--grid-floors", o.floors, "only cells on these floors (0 = lowest)")->delimiter(','),
      command.add_option("--grid-cells", o.cells, "only these cell ids")->delimiter(','),
  };
}

int runSceneGrid(const std::string& directory, const std::string& output, const WorkPlaneGridOptions& options,
                 bool verbose) {
  const SceneStore store = SceneStore::open(directory);
  const WorkPlaneGrid grid = placeWorkPlaneGrid(store, options);
  if (grid.sensors.empty()) {
    std::cerr << fmt::format("scene store {}: no room of the chosen cells has a point of a {:.2f} m grid {:.2f} m "
                             "from its walls; nothing written\n",
                             directory, options.spacing, options.inset);
    return 1;
  }
  writePtsFile(output, grid.sensors);
  std::map<uint32_t, std::pair<uint32_t, uint32_t>> perFloor;   // floor -> rooms, points
  for (const WorkPlaneRoom& room : grid.rooms) {
    perFloor[room.floor].first += 1;
    perFloor[room.floor].second += room.sensors;
    if (verbose)
      std::cout << fmt::format("  cell {:4} {:24} {} {}  floor y {:7.2f} m  {:8.2f} m2  {:5} points\n", room.cell,
                               room.name, levelWord(store), room.floor, room.floorHeight, room.floorArea, room.sensors);
  }
  for (const auto& [floor, counts] : perFloor)
    std::cout << fmt::format("{} {}: {} rooms, {} points\n", levelWord(store), floor, counts.first, counts.second);
  std::cout << fmt::format("{}: {} points in {} rooms, {:.2f} m above their floors, {:.2f} m apart\n", output,
                           grid.sensors.size(), grid.rooms.size(), options.height, options.spacing);
  return 0;
}

}  // namespace portico::cli
