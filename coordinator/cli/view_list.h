// A views file, for `portico render STORE --views FILE.json -o DIR/`: several
// views of one store rendered after one photon pass. The file is a JSON
// array of objects, one per view:
//
//   [{"name": "hall", "look_from": [1, 1.6, 2], "look_at": [5, 1.2, 2]},
//    {"name": "door", "look_from": [3, 1.6, 8], "look_at": [3, 1.2, 4],
//     "up": [0, 1, 0], "fov": 60, "width": 320, "height": 240, "spp": 4},
//    {"name": "corridor", "camera": "floor0-corridor"}]
//
// `name` (a safe file name: the image is DIR/<name>.<format>) is required,
// and either `camera` (a store camera's name, as `--camera`) or `look_from`
// and `look_at`, whose `up` and `fov` default to the store camera's;
// `width`, `height` and `spp` default to the command's options.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/job/job_settings.h"
#include "common/scene/store/scene_store.h"

namespace portico::cli {

struct View {
  std::string name;
  std::string cameraName;   // a store camera; empty: `camera`
  JobCamera camera;         // up and fov 0: the store camera's
  std::optional<uint32_t> width, height, spp;
};

// Every refusal is a std::invalid_argument of one line naming the file, the
// view (its place in the list, and its name when it has one) and the problem.
std::vector<View> readViewList(const std::string& path);
// The same for a parsed document; `origin` names it in errors.
std::vector<View> parseViewList(const nlohmann::json& document, const std::string& origin);
// What can be checked against the store before anything starts: an eye
// inside one of its cells, a direction to look.
void checkViewsAgainstStore(const std::vector<View>& views, const SceneStore& scene, const std::string& origin);

// One view's job: `base` with the view's camera, size and spp, writing
// directory/<name>.<extension>.
JobSettings viewSettings(const JobSettings& base, const View& view, const std::string& directory,
                         const std::string& extension);

}  // namespace portico::cli
