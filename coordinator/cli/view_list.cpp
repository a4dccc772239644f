#include "coordinator/cli/view_list.h"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <stdexcept>

#include "coordinator/job_limits.h"
#include "common/util/json_non_finite.h"

namespace portico::cli {

namespace {
constexpr size_t kMostViews = 10000;
constexpr size_t kLongestName = 100;

bool safeFileName(const std::string& name) {
  if (name.empty() || name.size() > kLongestName || name[0] == '.' || name[0] == '-') return false;
  for (unsigned char c : name)
    if (!std::isalnum(c) && c != '.' && c != '_' && c != '-') return false;
  return true;
}

// Reads one view. `fail` throws naming the view.
class ViewReader {
 public:
  ViewReader(const std::string& origin, size_t index) : origin_(origin), index_(index) {}

  [[noreturn]] void fail(const std::string& problem) const {
    const std::string name = name_.empty() ? "" : fmt::format(" (\"{}\")", name_);
    throw std::invalid_argument(fmt::format("{}: view {}{}: {}", origin_, index_ + 1, name, problem));
  }

  // The one place where a view's keys map onto its fields.
  View read(const nlohmann::json& entry) {
    if (!entry.is_object()) fail(fmt::format("is {}, not an object", entry.type_name()));
    View view;
    if (entry.contains("name")) {
      const auto& name = entry["name"];
      if (!name.is_string()) fail("\"name\" must be a string");
      name_ = name.get<std::string>();
      if (!safeFileName(name_))
        fail(fmt::format("\"name\" must be a safe file name (letters, digits, '.', '_', '-'; not starting with '.' "
                         "or '-'; at most {} characters)",
                         kLongestName));
      view.name = name_;
    }
    bool from = false, at = false;
    for (const auto& [key, value] : entry.items()) {
      if (key == "name") continue;
      if (key == "look_from") view.camera.lookFrom = point(key, value), from = true;
      else if (key == "look_at") view.camera.lookAt = point(key, value), at = true;
      else if (key == "up") view.camera.up = point(key, value);
      else if (key == "fov") view.camera.fovYDegrees = float(number(key, value, 1e-3, 179.999));
      else if (key == "width") view.width = whole(key, value, 1, limits::kMaxImageSide);
      else if (key == "height") view.height = whole(key, value, 1, limits::kMaxImageSide);
      else if (key == "spp") view.spp = whole(key, value, 1, limits::kMaxSpp);
      else if (key == "camera") view.cameraName = cameraName(key, value);
      else fail(fmt::format("unknown key \"{}\" (known: name, camera, look_from, look_at, up, fov, width, height, spp)",
                            key));
    }
    if (view.name.empty()) fail("\"name\" is missing");
    // One without the other would be the store camera's size: both or neither.
    if (view.width.has_value() != view.height.has_value()) fail("\"width\" and \"height\" go together");
    // A store camera (`--camera NAME`) or a camera of the view's own, not both.
    if (!view.cameraName.empty()) {
      if (from || at || view.camera.up != Vec3(0, 0, 0) || view.camera.fovYDegrees != 0)
        fail("\"camera\" names a store camera: it takes no look_from, look_at, up or fov");
      return view;
    }
    if (!from) fail("\"look_from\" is missing (or name a store camera with \"camera\")");
    if (!at) fail("\"look_at\" is missing");
    return view;
  }

 private:
  std::string cameraName(const std::string& key, const nlohmann::json& value) const {
    if (!value.is_string() || value.get<std::string>().empty())
      fail(fmt::format("\"{}\" must be a store camera's name (scene info lists them)", key));
    return value.get<std::string>();
  }

  double number(const std::string& key, const nlohmann::json& value, double least, double most) const {
    if (value.is_string())
      if (const auto literal = nonFiniteLiteral(value.get<std::string>()))
        fail(fmt::format("\"{}\" is {}, not a number", key, *literal));
    if (!value.is_number()) fail(fmt::format("\"{}\" must be a number, not {}", key, value.type_name()));
    const double x = value.get<double>();
    if (!std::isfinite(x) || x < least || x > most)
      fail(fmt::format("\"{}\" {} must be from {:g} to {:g}", key, value.dump(), least, most));
    return x;
  }

  uint32_t whole(const std::string& key, const nlohmann::json& value, int64_t least, int64_t most) const {
    const bool inRange = value.is_number_unsigned()  ? value.get<uint64_t>() >= uint64_t(least) &&
                                                          value.get<uint64_t>() <= uint64_t(most)
                         : value.is_number_integer() ? value.get<int64_t>() >= least && value.get<int64_t>() <= most
                                                     : false;
    if (!inRange) fail(fmt::format("\"{}\" {} must be a whole number from {} to {}", key, value.dump(), least, most));
    return uint32_t(value.get<uint64_t>());
  }

  Vec3 point(const std::string& key, const nlohmann::json& value) const {
    if (!value.is_array() || value.size() != 3) fail(fmt::format("\"{}\" must be three numbers [x, y, z]", key));
    float v[3];
    for (size_t i = 0; i < 3; ++i) {
      v[i] = float(number(fmt::format("{}[{}]", key, i), value[i], -1e30, 1e30));
      if (!std::isfinite(v[i])) fail(fmt::format("\"{}[{}]\" is not a finite number", key, i));
    }
    return Vec3(v[0], v[1], v[2]);
  }

  const std::string& origin_;
  size_t index_;
  std::string name_;
};
}  // namespace

std::vector<View> parseViewList(const nlohmann::json& document, const std::string& origin) {
  if (!document.is_array()) throw std::invalid_argument(fmt::format("{}: must be a JSON array of views", origin));
  if (document.empty()) throw std::invalid_argument(fmt::format("{}: lists no view", origin));
  if (document.size() > kMostViews)
    throw std::invalid_argument(fmt::format("{}: lists {} views: at most {}", origin, document.size(), kMostViews));
  std::vector<View> views;
  std::set<std::string> names;
  for (size_t i = 0; i < document.size(); ++i) {
    ViewReader reader(origin, i);
    View view = reader.read(document[i]);
    if (!names.insert(view.name).second) reader.fail("its name is another view's too: names must differ");
    views.push_back(std::move(view));
  }
  return views;
}

std::vector<View> readViewList(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument(fmt::format("{}: cannot be read", path));
  const std::string text(std::istreambuf_iterator<char>(in), {});
  nlohmann::json document;
  const std::string marked = markNonFiniteLiterals(text);
  try {
    document = nlohmann::json::parse(marked);
  } catch (const nlohmann::json::parse_error& e) {
    throw std::invalid_argument(fmt::format("{}: not JSON (byte {})", path, e.byte));
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument(fmt::format("{}: not JSON: {}", path, describeJsonError(marked, e)));
  }
  return parseViewList(document, path);
}

void checkViewsAgainstStore(const std::vector<View>& views, const SceneStore& scene, const std::string& origin) {
  for (size_t i = 0; i < views.size(); ++i) {
    const View& view = views[i];
    const auto fail = [&](const std::string& problem) {
      throw std::invalid_argument(fmt::format("{}: view {} (\"{}\"): {}", origin, i + 1, view.name, problem));
    };
    if (!view.cameraName.empty()) {
      if (!scene.findCamera(view.cameraName))
        fail(fmt::format("\"camera\" '{}': scene {} has no camera of that name (scene info lists them)",
                         view.cameraName, scene.directory()));
      continue;
    }
    if (view.camera.lookAt == view.camera.lookFrom) fail("\"look_at\" is the \"look_from\" point: no direction to look");
    if (!scene.locateCell(view.camera.lookFrom))
      fail(fmt::format("\"look_from\" {},{},{} is outside every cell of scene {}", view.camera.lookFrom.x,
                       view.camera.lookFrom.y, view.camera.lookFrom.z, scene.directory()));
  }
}

JobSettings viewSettings(const JobSettings& base, const View& view, const std::string& directory,
                         const std::string& extension) {
  JobSettings settings = base;
  if (view.cameraName.empty())
    settings.camera = view.camera;
  else
    settings.cameraName = view.cameraName;
  if (view.width) settings.width = *view.width;
  if (view.height) settings.height = *view.height;
  if (view.spp) settings.spp = *view.spp;
  settings.output = (std::filesystem::path(directory) / (view.name + "." + extension)).string();
  return settings;
}

}  // namespace portico::cli
