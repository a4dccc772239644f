#include "coordinator/cli/scene_import_ifc.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>

namespace portico::cli {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

json readJson(const std::string& path) {
  std::ifstream in(path);
  json value = json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (value.is_discarded() || !value.is_object())
    throw std::runtime_error(fmt::format("{}: not the converter's JSON (a converter of another version?)", path));
  return value;
}

json xyz(const Vec3& v) { return json::array({v.x, v.y, v.z}); }

// The rooms found, for conversion.json: their air and where their lamp and camera went.
json samplesJson(const FoundRoom& room) {
  json samples = json::array();
  for (const Vec3& p : room.samples) samples.push_back(xyz(p));
  return samples;
}

// Outdoor air the building shelters, for the watertightness check: where a room lost a wall.
json shelteredAirJson(const ImportSummary& summary, float voxelSize) {
  json pockets = json::array();
  for (const FoundRoom& pocket : summary.shelteredAir)
    pockets.push_back({{"name", pocket.name},
                       {"air_m3", double(pocket.airVoxels) * voxelSize * voxelSize * voxelSize},
                       {"air_lo", xyz(pocket.air.lo)},
                       {"air_hi", xyz(pocket.air.hi)},
                       {"voxel", voxelSize},
                       {"samples", samplesJson(pocket)}});
  return pockets;
}

json foundRoomsJson(const ImportSummary& summary, float voxelSize) {
  json rooms = json::array();
  for (const FoundRoom& room : summary.rooms) {
    const json samples = samplesJson(room);
    rooms.push_back({{"name", room.name},
                     {"air_m3", double(room.airVoxels) * voxelSize * voxelSize * voxelSize},
                     {"floor_m2", room.floorArea},
                     {"air_lo", xyz(room.air.lo)},
                     {"air_hi", xyz(room.air.hi)},
                     {"centre", xyz(room.centre)},
                     {"floor", room.floor},
                     {"ceiling", room.ceiling},
                     {"voxel", voxelSize},
                     {"samples", samples}});
  }
  return rooms;
}

void writeJson(const json& value, const std::string& path) {
  std::ofstream out(path);
  out << value.dump(1) << "\n";
  if (!out) throw std::runtime_error(fmt::format("{}: cannot write", path));
}

}  // namespace

ImportSummary importIfcModel(const std::string& ifc, const std::string& store, const ImportOptions& options,
                             const IfcOptions& ifcOptions) {
  // The converter's files live beside the store while it is written, then go (unless kept).
  const std::string converted = ifcOptions.keepConversion.empty() ? store + ".ifc-conversion" : ifcOptions.keepConversion;
  fs::remove_all(converted);
  struct Cleanup {
    std::string directory;
    bool keep;
    ~Cleanup() {
      if (!keep) fs::remove_all(directory);
    }
  } cleanup{converted, !ifcOptions.keepConversion.empty()};

  const std::string building = convertIfc(ifc, converted, ifcOptions);
  json conversion = readJson(converted + "/conversion.json");
  ImportOptions importOptions = options;
  const json* findRooms = conversion.contains("find_rooms") ? &conversion["find_rooms"] : nullptr;
  if (findRooms) {
    std::cerr << fmt::format("{}: {}: finding rooms in its geometry instead\n", ifc,
                             findRooms->value("reason", std::string("no usable IfcSpace")));
    importOptions.findRooms = true;
    importOptions.rooms.solidsAreClosed = true;   // IfcOpenShell's solids: a footing's inside is no room
    importOptions.lampPerFoundRoom = findRooms->value("lamps", false);
    importOptions.cameraPerFoundRoom = true;
  }
  ImportSummary summary;
  try {
    summary = importBuilding({building}, store, importOptions);
  } catch (const std::runtime_error& e) {
    // Name the model, not the converter's files (they are gone).
    std::string message = e.what();
    if (const size_t at = message.find(building); at != std::string::npos) message.replace(at, building.size(), ifc);
    throw std::runtime_error(message);
  }
  if (findRooms) {
    json& s = conversion["summary"];
    s["rooms_found"] = summary.rooms.size();
    s["cells"] = summary.roomCells;
    s["portals"] = summary.roomPortals;
    s["lights"] = summary.lights;
    s["cameras"] = s.value("cameras", 0) + summary.rooms.size();
    s["voxel_size"] = summary.roomVoxelSize;
    conversion["found_rooms"] = foundRoomsJson(summary, summary.roomVoxelSize);
    conversion["sheltered_outdoors"] = shelteredAirJson(summary, summary.roomVoxelSize);
    double shelteredVoxels = 0;
    for (const FoundRoom& pocket : summary.shelteredAir) shelteredVoxels += double(pocket.airVoxels);
    s["sheltered_outdoors_m3"] = shelteredVoxels * std::pow(double(summary.roomVoxelSize), 3);
  }
  writeJson(conversion, store + "/conversion.json");
  if (!ifcOptions.keepConversion.empty()) writeJson(conversion, converted + "/conversion.json");
  return summary;
}

}  // namespace portico::cli
