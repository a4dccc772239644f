// building.json -> BuildingDescription. Every key is checked: known keys
// strictly, descriptive ones (the reference scenes carry descriptions,
// derived camera vectors, triangle counts) and '_'-prefixed ones are
// ignored, any other is refused by name. Every error is one line that
// starts with the file and names what is wrong.
#include "common/scene/import/building_json.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <tuple>
#include <vector>

#include "common/analysis/sensor.h"
#include "common/photometry/ies_file.h"
#include "common/photometry/lamp_colour.h"
#include "common/scene/store/portal_geometry.h"
#include "common/util/json_non_finite.h"

namespace portico {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// Keys that describe rather than define (the reference scenes carry them):
// accepted anywhere and ignored, like every key starting with '_'.
constexpr std::string_view kDescriptiveKeys[] = {
    "description", "note", "notes", "comment", "triangles", "area_m2", "camera_derived", "camera_model",
    "coordinate_system", "emission_model", "material_model", "geometry", "pixel_values", "room_aabb"};

bool isDescriptiveKey(const std::string& key) {
  return key.rfind('_', 0) == 0 ||
         std::find(std::begin(kDescriptiveKeys), std::end(kDescriptiveKeys), key) != std::end(kDescriptiveKeys);
}

class Reader {
 public:
  explicit Reader(std::string path) : path_(std::move(path)) {}

  [[noreturn]] void fail(const std::string& problem) const {
    throw std::runtime_error(fmt::format("{}: {}", path_, problem));
  }

  float number(const json& value, const std::string& what) const {
    if (value.is_string()) {
      const std::string text = value.get<std::string>();
      if (const auto literal = nonFiniteLiteral(text)) fail(fmt::format("{} is {}, not a finite number", what, *literal));
    }
    if (!value.is_number()) fail(fmt::format("{} must be a number, not {}", what, value.type_name()));
    const double number = value.get<double>();
    if (!std::isfinite(number) || !std::isfinite(static_cast<float>(number)))
      fail(fmt::format("{} = {} is not a finite number", what, number));
    return static_cast<float>(number);
  }

  Vec3 vec3(const json& value, const std::string& what) const {
    if (!value.is_array() || value.size() != 3) fail(fmt::format("{} must be an array of 3 numbers", what));
    return Vec3(number(value[0], what + "[0]"), number(value[1], what + "[1]"), number(value[2], what + "[2]"));
  }

  std::string string(const json& value, const std::string& what) const {
    if (!value.is_string()) fail(fmt::format("{} must be a string, not {}", what, value.type_name()));
    return value.get<std::string>();
  }

  uint32_t positiveInteger(const json& value, const std::string& what, uint32_t maximum) const {
    const float number = this->number(value, what);
    if (number != std::floor(number) || number < 1 || number > maximum)
      fail(fmt::format("{} = {} must be a whole number in [1, {}]", what, number, maximum));
    return static_cast<uint32_t>(number);
  }

  // Refuses a key of `object` that is neither in `known` nor descriptive
  // (see kDescriptiveKeys): a misspelt "emision" would otherwise silently
  // turn a light off.
  void requireKnownKeys(const json& object, const std::string& what,
                        std::initializer_list<std::string_view> known) const {
    for (const auto& [key, value] : object.items()) {
      if (std::find(known.begin(), known.end(), key) != known.end() || isDescriptiveKey(key)) continue;
      std::string names;
      for (std::string_view name : known) names += fmt::format("{}{}", names.empty() ? "" : ", ", name);
      fail(fmt::format("{}: unknown key \"{}\" (known: {}; keys starting with '_' are ignored)", what, key, names));
    }
  }

  const json* member(const json& object, const char* key) const {
    auto it = object.find(key);
    return it == object.end() ? nullptr : &*it;
  }
  const json& required(const json& object, const char* key, const std::string& what) const {
    const json* value = member(object, key);
    if (value == nullptr) fail(fmt::format("{} has no \"{}\"", what, key));
    return *value;
  }

 private:
  std::string path_;
};

json parseFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(fmt::format("{}: cannot be opened", path));
  std::stringstream text;
  text << in.rdbuf();
  const std::string marked = markNonFiniteLiterals(text.str());
  try {
    return json::parse(marked);
  } catch (const json::exception& e) {
    throw std::runtime_error(fmt::format("{}: not valid JSON: {}", path, describeJsonError(marked, e)));
  }
}

void readUnits(const Reader& reader, const json& root) {
  const json* units = reader.member(root, "units");
  if (units == nullptr) return;
  const std::string value = reader.string(*units, "\"units\"");
  static const std::set<std::string> kMetres{"m", "metre", "metres", "meter", "meters"};
  if (!kMetres.count(value))
    reader.fail(fmt::format("\"units\" is '{}'; portico reads metres only (scale the meshes to metres)", value));
}

std::vector<BuildingCell> readCells(const Reader& reader, const json& list) {
  if (!list.is_array()) reader.fail("\"cells\" must be an array");
  std::vector<BuildingCell> cells;
  std::set<std::string> names;
  for (size_t i = 0; i < list.size(); ++i) {
    const json& entry = list[i];
    std::string what = fmt::format("cells[{}]", i);
    if (!entry.is_object()) reader.fail(what + " must be an object");
    BuildingCell cell;
    cell.name = reader.string(reader.required(entry, "name", what), what + ".name");
    if (cell.name.empty()) reader.fail(what + ".name is empty");
    what = fmt::format("cell '{}'", cell.name);
    if (!names.insert(cell.name).second) reader.fail(fmt::format("{} is defined twice", what));
    reader.requireKnownKeys(entry, what, {"name", "aabb"});
    const json& aabb = reader.required(entry, "aabb", what);
    if (!aabb.is_object()) reader.fail(what + ": \"aabb\" must be an object with \"min\" and \"max\"");
    reader.requireKnownKeys(aabb, what + " aabb", {"min", "max"});
    cell.bounds.lo = reader.vec3(reader.required(aabb, "min", what + " aabb"), what + " aabb.min");
    cell.bounds.hi = reader.vec3(reader.required(aabb, "max", what + " aabb"), what + " aabb.max");
    for (int axis = 0; axis < 3; ++axis)
      if (!(cell.bounds.lo[axis] < cell.bounds.hi[axis]))
        reader.fail(fmt::format("{}: aabb.min[{}] = {} is not below aabb.max[{}] = {}", what, axis,
                                cell.bounds.lo[axis], axis, cell.bounds.hi[axis]));
    cells.push_back(std::move(cell));
  }
  if (cells.empty()) reader.fail("\"cells\" is empty (leave it out for one cell around the whole scene)");
  return cells;
}

const BuildingCell* findCell(const std::optional<std::vector<BuildingCell>>& cells, const std::string& name) {
  if (!cells) return nullptr;
  for (const BuildingCell& cell : *cells)
    if (cell.name == name) return &cell;
  return nullptr;
}

std::string knownCells(const std::optional<std::vector<BuildingCell>>& cells) {
  if (!cells) return "the file has no \"cells\"";
  std::string names;
  for (const BuildingCell& cell : *cells) names += (names.empty() ? "" : ", ") + cell.name;
  return "known: " + names;
}

Vec3 radiance(const Reader& reader, const json& value, const std::string& what) {
  const Vec3 v = reader.vec3(value, what);
  if (std::min({v.x, v.y, v.z}) < 0.0f)
    reader.fail(fmt::format("{} [{}, {}, {}] must not be negative", what, v.x, v.y, v.z));
  return v;
}

double readLumens(const Reader& reader, const json& value, const std::string& what) {
  reader.number(value, what + " lumens");   // refuses anything but a finite number, naming it
  const double lumens = value.get<double>();
  if (!(lumens > 0)) reader.fail(fmt::format("{}: lumens = {} must be above 0", what, lumens));
  return lumens;
}

// A lamp's colour at luminance Y = 1: "colour_temperature" (kelvin) or
// "colour" ([r, g, b]), else kDefaultColourTemperature.
Vec3 readLampColour(const Reader& reader, const json& entry, const std::string& what) {
  const json* temperature = reader.member(entry, "colour_temperature");
  const json* colour = reader.member(entry, "colour");
  if (temperature && colour) reader.fail(what + ": give \"colour_temperature\" or \"colour\", not both");
  if (colour) {
    const Vec3 rgb = reader.vec3(*colour, what + " colour");
    if (std::min({rgb.x, rgb.y, rgb.z}) < 0.0f || !(maxComponent(rgb) > 0.0f))
      reader.fail(fmt::format("{}: colour [{}, {}, {}] must not be negative or black", what, rgb.x, rgb.y, rgb.z));
    return unitLuminanceColour(rgb);
  }
  double kelvin = kDefaultColourTemperature;
  if (temperature) {
    reader.number(*temperature, what + " colour_temperature");
    kelvin = temperature->get<double>();
    if (const std::string problem = colourTemperatureProblem(kelvin); !problem.empty())
      reader.fail(fmt::format("{}: {}", what, problem));
  }
  return colourOfTemperature(kelvin);
}

// "lumens" and its colour, when the entry gives them: "colour_temperature"
// (kelvin) or "colour" ([r, g, b]), else kDefaultColourTemperature.
std::optional<LampOutput> readLampOutput(const Reader& reader, const json& entry, const std::string& what) {
  const json* lumens = reader.member(entry, "lumens");
  const json* temperature = reader.member(entry, "colour_temperature");
  const json* colour = reader.member(entry, "colour");
  if (!lumens) {
    if (temperature || colour)
      reader.fail(fmt::format("{}: \"{}\" needs \"lumens\" (the lamp's luminous flux)", what,
                              temperature ? "colour_temperature" : "colour"));
    return std::nullopt;
  }
  LampOutput output;
  output.lumens = readLumens(reader, *lumens, what);
  output.colour = readLampColour(reader, entry, what);
  return output;
}

// An object's "glass": {"transmittance": [r, g, b], "ior": n}; not with an albedo or emission.
BuildingObject::Glass readGlass(const Reader& reader, const json& entry, const std::string& what,
                                const BuildingObject& object) {
  if (object.albedo || object.emission || object.lumens)
    reader.fail(what + ": \"glass\" is a material of its own; give no \"albedo\", \"emission\" or \"lumens\" with it");
  if (!entry.is_object()) reader.fail(what + ": \"glass\" must be an object with \"transmittance\" (and \"ior\")");
  reader.requireKnownKeys(entry, what + " glass", {"transmittance", "ior"});
  BuildingObject::Glass glass;
  glass.transmittance = reader.vec3(reader.required(entry, "transmittance", what + " glass"), what + " glass.transmittance");
  if (std::min({glass.transmittance.x, glass.transmittance.y, glass.transmittance.z}) < 0.0f ||
      maxComponent(glass.transmittance) > 1.0f || !(maxComponent(glass.transmittance) > 0.0f))
    reader.fail(fmt::format("{}: glass transmittance [{}, {}, {}] must lie within [0, 1], not all 0", what,
                            glass.transmittance.x, glass.transmittance.y, glass.transmittance.z));
  if (const json* ior = reader.member(entry, "ior")) {
    glass.ior = reader.number(*ior, what + " glass.ior");
    if (!(glass.ior >= 1.0f && glass.ior <= 4.0f))
      reader.fail(fmt::format("{}: glass ior {} must be from 1 to 4", what, glass.ior));
  }
  return glass;
}

std::vector<BuildingObject> readObjects(const Reader& reader, const json& root, const fs::path& baseDirectory,
                                        const std::optional<std::vector<BuildingCell>>& cells) {
  const json& list = reader.required(root, "objects", "the file");
  if (!list.is_array() || list.empty()) reader.fail("\"objects\" must be a non-empty array");
  std::vector<BuildingObject> objects;
  for (size_t i = 0; i < list.size(); ++i) {
    const json& entry = list[i];
    BuildingObject object;
    object.index = i;
    std::string what = fmt::format("objects[{}]", i);
    if (!entry.is_object()) reader.fail(what + " must be an object");
    const json* obj = reader.member(entry, "obj");
    const json* mesh = reader.member(entry, "mesh");
    if (obj && mesh) reader.fail(what + " has both \"obj\" and \"mesh\"; give one mesh file");
    if (!obj && !mesh) reader.fail(what + " has no mesh file (\"obj\" or \"mesh\")");
    const std::string file = reader.string(obj ? *obj : *mesh, what + (obj ? ".obj" : ".mesh"));
    if (file.empty()) reader.fail(what + ": the mesh file name is empty");
    const fs::path meshPath(file);
    object.meshPath = (meshPath.is_absolute() ? meshPath : baseDirectory / meshPath).lexically_normal().string();
    if (const json* name = reader.member(entry, "name"))
      object.name = reader.string(*name, what + ".name");
    if (object.name.empty()) object.name = meshPath.stem().string();
    what = object.label();
    reader.requireKnownKeys(entry, what, {"obj", "mesh", "name", "cell", "albedo", "emission", "lumens",
                                          "colour_temperature", "colour", "glass"});

    if (const json* cell = reader.member(entry, "cell")) {
      object.cell = reader.string(*cell, what + ".cell");
      if (!findCell(cells, object.cell))
        reader.fail(fmt::format("{}: unknown cell '{}' ({})", what, object.cell, knownCells(cells)));
    } else if (cells) {
      reader.fail(fmt::format("{} has no \"cell\" (every object needs one when \"cells\" is given)", what));
    }

    if (const json* albedo = reader.member(entry, "albedo")) {
      const Vec3 value = reader.vec3(*albedo, what + " albedo");
      if (std::min({value.x, value.y, value.z}) < 0.0f || maxComponent(value) > 1.0f)
        reader.fail(fmt::format("{}: albedo [{}, {}, {}] must lie within [0, 1] (it is a reflectance)", what, value.x,
                                value.y, value.z));
      object.albedo = value;
    }
    const json* emission = reader.member(entry, "emission");
    if (emission && !emission->is_null()) object.emission = radiance(reader, *emission, what + " emission");
    object.lumens = readLampOutput(reader, entry, what);
    if (object.lumens && emission && !emission->is_null())
      reader.fail(what + ": give \"emission\" (radiance) or \"lumens\", not both");
    if (const json* glass = reader.member(entry, "glass")) object.glass = readGlass(reader, *glass, what, object);
    objects.push_back(std::move(object));
  }
  return objects;
}

// Photometric files already read, by resolved path: the distribution and
// the file's luminous opening.
struct LuminaireFile {
  std::shared_ptr<const LuminousIntensity> intensity;
  LuminousOpening opening;
};
using LuminaireFiles = std::map<std::string, LuminaireFile>;

// A unit vector from `value`, named `what` in messages.
Vec3 unitVector(const Reader& reader, const json& value, const std::string& what) {
  const Vec3 v = reader.vec3(value, what);
  if (!(length(v) > 0.0f)) reader.fail(what + " is a zero vector; it gives a direction");
  return normalize(v);
}

// An "ies" light: a point luminaire at "position", its nadir along "aim"
// (default straight down) and its C0 direction along "c0" (default +x, or
// +z when the aim is near the x axis; made perpendicular to the aim).
void readLuminaire(const Reader& reader, const json& entry, const json& ies, const std::string& what,
                   const fs::path& baseDirectory, LuminaireFiles& distributions, BuildingLight& light) {
  reader.requireKnownKeys(entry, what, {"name", "cell", "ies", "position", "aim", "c0", "lumens", "colour_temperature",
                                        "colour", "opening"});
  const std::string file = reader.string(ies, what + ".ies");
  if (file.empty()) reader.fail(what + ": the ies file name is empty");
  const fs::path iesPath(file);
  light.iesPath = (iesPath.is_absolute() ? iesPath : baseDirectory / iesPath).lexically_normal().string();
  LuminaireFile& read = distributions[light.iesPath];
  if (!read.intensity) {
    try {
      const IesPhotometry ies = readIesFile(light.iesPath);
      read.intensity = std::make_shared<const LuminousIntensity>(ies.grid, fs::path(light.iesPath).filename().string());
      read.opening = ies.opening;
    } catch (const std::runtime_error& e) {
      reader.fail(fmt::format("{}: {}", what, e.what()));
    }
  }
  const std::shared_ptr<const LuminousIntensity>& intensity = read.intensity;
  light.opening = read.opening;
  // "opening": [width, length, height] in metres, as an LM-63 file gives
  // them (negative sizes: round shapes), instead of the file's.
  if (const json* opening = reader.member(entry, "opening")) {
    const Vec3 given = reader.vec3(*opening, what + " opening");
    try {
      light.opening = LuminousOpening::fromLm63(given.x, given.y, given.z);
    } catch (const std::invalid_argument& e) {
      reader.fail(fmt::format("{}: opening: {}", what, e.what()));
    }
  }
  if (!(intensity->lumens() > 0)) reader.fail(fmt::format("{}: {} emits no light (every candela value is 0)", what, file));
  light.intensity = intensity;
  light.shape = LightShape::Point;
  light.corner = reader.vec3(reader.required(entry, "position", what), what + " position");
  const json* aimValue = reader.member(entry, "aim");
  const Vec3 aim = aimValue ? unitVector(reader, *aimValue, what + " aim") : Vec3(0, -1, 0);
  Vec3 c0 = std::abs(aim.x) < 0.9f ? Vec3(1, 0, 0) : Vec3(0, 0, 1);
  if (const json* c0Value = reader.member(entry, "c0")) c0 = unitVector(reader, *c0Value, what + " c0");
  const Vec3 across = c0 - aim * dot(aim, c0);
  if (!(length(across) > 1e-3f)) reader.fail(what + ": c0 is parallel to aim; it must point across it");
  light.edge1 = aim;
  light.edge2 = normalize(across);
  const Vec3 colour = readLampColour(reader, entry, what);
  // Its own candela values, or scaled to give "lumens".
  const json* lumens = reader.member(entry, "lumens");
  const double scale = lumens ? readLumens(reader, *lumens, what) / intensity->lumens() : 1.0;
  light.radiance = colour * float(scale / kLuminousEfficacy);
}

// A "quad" or "triangle" light with "radiance" or "lumens".
void readAreaLight(const Reader& reader, const json& entry, const std::string& what, BuildingLight& light) {
  reader.requireKnownKeys(entry, what, {"name", "cell", "quad", "triangle", "radiance", "lumens", "colour_temperature",
                                        "colour"});
  const json* quad = reader.member(entry, "quad");
  const json* triangle = reader.member(entry, "triangle");
  if ((quad != nullptr) == (triangle != nullptr))
    reader.fail(fmt::format("{} needs one shape: \"quad\": {{\"corner\", \"edge1\", \"edge2\"}} or "
                            "\"triangle\": [[x, y, z], [x, y, z], [x, y, z]]",
                            what));
  if (quad) {
    if (!quad->is_object()) reader.fail(what + ": \"quad\" must be an object with \"corner\", \"edge1\", \"edge2\"");
    reader.requireKnownKeys(*quad, what + " quad", {"corner", "edge1", "edge2"});
    light.corner = reader.vec3(reader.required(*quad, "corner", what + " quad"), what + " quad.corner");
    light.edge1 = reader.vec3(reader.required(*quad, "edge1", what + " quad"), what + " quad.edge1");
    light.edge2 = reader.vec3(reader.required(*quad, "edge2", what + " quad"), what + " quad.edge2");
  } else {
    if (!triangle->is_array() || triangle->size() != 3)
      reader.fail(what + ": \"triangle\" must be an array of 3 points [x, y, z]");
    const Vec3 a = reader.vec3((*triangle)[0], what + " triangle[0]");
    light.shape = LightShape::Triangle;
    light.corner = a;
    light.edge1 = reader.vec3((*triangle)[1], what + " triangle[1]") - a;
    light.edge2 = reader.vec3((*triangle)[2], what + " triangle[2]") - a;
  }
  if (!(length(cross(light.edge1, light.edge2)) > 0.0f))
    reader.fail(fmt::format("{}: the {} has zero area (its edges are parallel or zero)", what,
                            quad ? "quad" : "triangle"));
  const std::optional<LampOutput> lumens = readLampOutput(reader, entry, what);
  const json* given = reader.member(entry, "radiance");
  if (lumens && given) reader.fail(what + ": give \"radiance\" or \"lumens\", not both");
  if (!lumens && !given) reader.fail(what + " has no \"radiance\" (W m^-2 sr^-1 per channel) or \"lumens\"");
  if (lumens) {
    AreaLight shape;   // its area, as the store will compute the light's power
    shape.shape = light.shape;
    shape.edge1 = light.edge1;
    shape.edge2 = light.edge2;
    light.radiance = radianceOfLumens(lumens->lumens, lumens->colour, shape.area());
  } else {
    light.radiance = radiance(reader, *given, what + " radiance");
  }
  if (!(maxComponent(light.radiance) > 0.0f)) reader.fail(what + ": radiance is zero; a light must emit");
}

// One entry of "lights": {"quad": {"corner", "edge1", "edge2"}} or
// {"triangle": [p0, p1, p2]}, with "radiance" or "lumens"; or an "ies"
// luminaire; and (given cells) "cell".
BuildingLight readLight(const Reader& reader, const json& entry, size_t index,
                        const std::optional<std::vector<BuildingCell>>& cells, const fs::path& baseDirectory,
                        LuminaireFiles& distributions) {
  BuildingLight light;
  light.index = index;
  std::string what = fmt::format("lights[{}]", index);
  if (!entry.is_object()) reader.fail(what + " must be an object");
  light.name = fmt::format("light-{}", index);
  if (const json* name = reader.member(entry, "name")) light.name = reader.string(*name, what + ".name");
  what = light.label();
  if (const json* ies = reader.member(entry, "ies")) {
    readLuminaire(reader, entry, *ies, what, baseDirectory, distributions, light);
  } else {
    readAreaLight(reader, entry, what, light);
  }
  if (const json* cell = reader.member(entry, "cell")) {
    light.cell = reader.string(*cell, what + ".cell");
    if (!findCell(cells, light.cell))
      reader.fail(fmt::format("{}: unknown cell '{}' ({})", what, light.cell, knownCells(cells)));
  } else if (cells) {
    reader.fail(fmt::format("{} has no \"cell\" (every light needs one when \"cells\" is given)", what));
  }
  return light;
}

std::vector<BuildingLight> readLights(const Reader& reader, const json& list,
                                      const std::optional<std::vector<BuildingCell>>& cells,
                                      const fs::path& baseDirectory) {
  if (!list.is_array()) reader.fail("\"lights\" must be an array");
  std::vector<BuildingLight> lights;
  LuminaireFiles distributions;   // each photometric file read once, however many luminaires use it
  for (size_t i = 0; i < list.size(); ++i)
    lights.push_back(readLight(reader, list[i], i, cells, baseDirectory, distributions));
  return lights;
}

std::vector<BuildingPortal> readPortals(const Reader& reader, const json& list,
                                        const std::optional<std::vector<BuildingCell>>& cells) {
  if (!list.is_array()) reader.fail("\"portals\" must be an array");
  if (!list.empty() && !cells) reader.fail("\"portals\" needs \"cells\" to join");
  std::vector<BuildingPortal> portals;
  // Where each (pair of cells, polygon) was first given, and portals per cell.
  std::map<std::tuple<std::string, std::string, std::vector<float>>, size_t> firstGiven;
  std::map<std::string, uint32_t> perCell;
  for (size_t i = 0; i < list.size(); ++i) {
    const json& entry = list[i];
    const std::string what = fmt::format("portals[{}]", i);
    if (!entry.is_object()) reader.fail(what + " must be an object");
    BuildingPortal portal;
    portal.index = i;
    reader.requireKnownKeys(entry, what, {"between", "polygon"});
    const json& between = reader.required(entry, "between", what);
    if (!between.is_array() || between.size() != 2)
      reader.fail(what + ": \"between\" must be an array of two cell names");
    portal.cellA = reader.string(between[0], what + ".between[0]");
    portal.cellB = reader.string(between[1], what + ".between[1]");
    for (const std::string& name : {portal.cellA, portal.cellB})
      if (!findCell(cells, name)) reader.fail(fmt::format("{}: unknown cell '{}' ({})", what, name, knownCells(cells)));
    if (portal.cellA == portal.cellB) reader.fail(fmt::format("{} joins cell '{}' to itself", what, portal.cellA));
    const std::string label = fmt::format("{} ({} - {})", what, portal.cellA, portal.cellB);
    const json& polygon = reader.required(entry, "polygon", label);
    if (!polygon.is_array()) reader.fail(label + ": \"polygon\" must be an array of [x, y, z] points");
    for (size_t p = 0; p < polygon.size(); ++p)
      portal.polygon.push_back(reader.vec3(polygon[p], fmt::format("{} polygon[{}]", label, p)));
    if (std::string problem = portalShapeProblem(portal.polygon); !problem.empty())
      reader.fail(fmt::format("{}: polygon {}", label, problem));
    // A portal is where its two cells meet: it must lie on a face of both boxes.
    for (const std::string& name : {portal.cellA, portal.cellB})
      if (std::string problem = portalBoundaryProblem(findCell(cells, name)->bounds, portal.polygon); !problem.empty())
        reader.fail(fmt::format("{}: polygon is not on the boundary of cell '{}': {}", label, name, problem));
    std::vector<float> corners;
    for (const Vec3& p : portal.polygon) corners.insert(corners.end(), {p.x, p.y, p.z});
    const auto [first, fresh] = firstGiven.emplace(
        std::make_tuple(std::min(portal.cellA, portal.cellB), std::max(portal.cellA, portal.cellB), corners), i);
    if (!fresh) reader.fail(fmt::format("{}: duplicates portals[{}]", label, first->second));
    for (const std::string& name : {portal.cellA, portal.cellB})
      if (++perCell[name] > kMaxPortalsPerCell)
        reader.fail(fmt::format("{}: cell '{}' has more than {} portals", label, name, kMaxPortalsPerCell));
    portals.push_back(std::move(portal));
  }
  return portals;
}

BuildingCamera readCamera(const Reader& reader, const json& entry, const std::string& what) {
  if (!entry.is_object()) reader.fail(what + " must be an object");
  reader.requireKnownKeys(entry, what, {"name", "origin", "target", "up", "fov_y_deg", "width", "height"});
  BuildingCamera result;
  Camera& camera = result.camera;
  camera.origin = reader.vec3(reader.required(entry, "origin", what), what + ".origin");
  camera.target = reader.vec3(reader.required(entry, "target", what), what + ".target");
  if (const json* up = reader.member(entry, "up")) camera.up = reader.vec3(*up, what + ".up");
  camera.fovYDegrees = 60.0f;
  if (const json* fov = reader.member(entry, "fov_y_deg"))
    camera.fovYDegrees = reader.number(*fov, what + ".fov_y_deg");
  camera.width = 512;
  camera.height = 384;
  if (const json* width = reader.member(entry, "width"))
    camera.width = reader.positiveInteger(*width, what + ".width", 65536);
  if (const json* height = reader.member(entry, "height"))
    camera.height = reader.positiveInteger(*height, what + ".height", 65536);
  if (!(camera.fovYDegrees > 0.0f && camera.fovYDegrees < 180.0f))
    reader.fail(fmt::format("{}: fov_y_deg = {} must lie in (0, 180) (the full vertical field of view)", what,
                            camera.fovYDegrees));
  if (camera.origin == camera.target) reader.fail(what + ": origin and target are the same point");
  if (length(cross(camera.target - camera.origin, camera.up)) == 0.0f)
    reader.fail(what + ": up is parallel to the viewing direction (or zero)");
  return result;
}

std::vector<BuildingCamera> readCameras(const Reader& reader, const json& root) {
  const json* single = reader.member(root, "camera");
  const json* list = reader.member(root, "cameras");
  if (single && list) reader.fail("has both \"camera\" and \"cameras\"; give one of them");
  std::vector<BuildingCamera> cameras;
  if (single) {
    cameras.push_back(readCamera(reader, *single, "camera"));
    cameras.back().name = kDefaultCameraName;
  } else if (list) {
    if (!list->is_array() || list->empty()) reader.fail("\"cameras\" must be a non-empty array");
    std::set<std::string> names;
    for (size_t i = 0; i < list->size(); ++i) {
      const std::string what = fmt::format("cameras[{}]", i);
      BuildingCamera camera = readCamera(reader, (*list)[i], what);
      camera.name = std::to_string(i);
      if (const json* name = reader.member((*list)[i], "name")) camera.name = reader.string(*name, what + ".name");
      if (!names.insert(camera.name).second)
        reader.fail(fmt::format("{}: camera name '{}' is used twice", what, camera.name));
      if (camera.name.empty() || camera.name.size() > kMaxCameraNameBytes)
        reader.fail(fmt::format("{}.name: must be 1 to {} bytes", what, kMaxCameraNameBytes));
      cameras.push_back(std::move(camera));
    }
  } else {
    reader.fail("has no \"camera\" (origin, target, up, fov_y_deg, width, height)");
  }
  for (BuildingCamera& camera : cameras) camera.camera.name = camera.name;
  return cameras;
}

// "site": {"latitude": 49.1, "longitude": 8.4, "north_azimuth": 0}, in
// degrees; north_azimuth may be left out (0: +Z is north).
SiteLocation readSite(const Reader& reader, const json& entry) {
  if (!entry.is_object())
    reader.fail("\"site\" must be an object with \"latitude\", \"longitude\" and \"north_azimuth\" (degrees)");
  reader.requireKnownKeys(entry, "site", {"latitude", "longitude", "north_azimuth"});
  // Read as double: a float's 24 bits would move a site by up to a metre.
  const auto degrees = [&](const char* key, std::string (*problem)(double)) {
    const std::string what = fmt::format("site.{}", key);
    const json& value = reader.required(entry, key, "site");
    reader.number(value, what);   // refuses anything but a finite number, naming it
    const double number = value.get<double>();
    if (const std::string wrong = problem(number); !wrong.empty()) reader.fail(fmt::format("{} = {} {}", what, number, wrong));
    return number;
  };
  SiteLocation site;
  site.latitudeDegrees = degrees("latitude", latitudeProblem);
  site.longitudeDegrees = degrees("longitude", longitudeProblem);
  if (reader.member(entry, "north_azimuth")) site.northAzimuthDegrees = degrees("north_azimuth", northAzimuthProblem);
  return site;
}

}  // namespace

std::string BuildingObject::label() const { return fmt::format("objects[{}] ('{}')", index, name); }
std::string BuildingLight::label() const { return fmt::format("lights[{}] ('{}')", index, name); }

BuildingDescription readBuildingJson(const std::string& path) {
  const json root = parseFile(path);
  const Reader reader(path);
  if (!root.is_object()) reader.fail("the top level must be a JSON object");
  // "site" (latitude, longitude, north) is read by `render --sun-time` (docs/daylight.md).
  reader.requireKnownKeys(root, "top level",
                          {"name", "units", "objects", "lights", "cells", "portals", "camera", "cameras", "site"});
  BuildingDescription building;
  building.path = path;
  building.name = fs::path(path).stem().string();
  if (const json* name = reader.member(root, "name")) building.name = reader.string(*name, "\"name\"");
  readUnits(reader, root);
  if (const json* cells = reader.member(root, "cells")) building.cells = readCells(reader, *cells);
  building.objects = readObjects(reader, root, fs::path(path).parent_path(), building.cells);
  if (const json* lights = reader.member(root, "lights"))
    building.lights = readLights(reader, *lights, building.cells, fs::path(path).parent_path());
  if (const json* portals = reader.member(root, "portals"))
    building.portals = readPortals(reader, *portals, building.cells);
  building.cameras = readCameras(reader, root);
  if (const json* site = reader.member(root, "site")) building.site = readSite(reader, *site);
  return building;
}

}  // namespace portico
