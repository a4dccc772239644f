// The options and arguments of `portico scene generate|import|info|export|plan|grid|ies`.
#include <CLI/CLI.hpp>

#include <memory>
#include <string>
#include <vector>

#include "common/scene/import/building_importer.h"
#include "coordinator/cli/command_table.h"
#include "coordinator/cli/commands.h"
#include "coordinator/cli/scene_export.h"
#include "coordinator/cli/work_plane_grid_command.h"

namespace portico::cli {

namespace {

void addGenerate(CLI::App& scene, CommandTable& table) {
  struct Options {
    std::string preset, store;
    uint64_t seed = 1;
    uint32_t floors = 0;
    PanelLighting panels;
  };
  auto o = std::make_shared<Options>();
  auto* generate = scene.add_subcommand("generate", "generate a building into a scene store");
  generate->add_option("--preset", o->preset, "building preset: demo, l-shape, z-building, octagon, soda-hall, tower")->required();
  generate->add_option("--seed", o->seed, "random seed of the furnishing")->capture_default_str();
  generate->add_option("--floors", o->floors, "floors of the tower preset (default 1); the other presets have their own");
  generate->add_option_function<double>(
      "--panel-lumens", [o](double lumens) { o->panels.lumens = lumens; },
      "luminous flux of every ceiling panel, lm (default: 6244 lm per m^2 of panel, 2248 lm for a 0.6 m square)");
  generate->add_option_function<double>(
      "--panel-colour-temperature", [o](double kelvin) { o->panels.colourTemperature = kelvin; },
      "colour temperature of the ceiling panels, K, 1667-25000 (default: about 5700 K)");
  generate->add_option("STORE", o->store, "scene store directory to write")->required();
  table.add(generate, [o] { return runSceneGenerate(o->preset, o->seed, o->floors, o->store, o->panels); });
}

void addImport(CLI::App& scene, CommandTable& table) {
  struct Options {
    std::vector<std::string> inputs;
    ImportOptions import;
    std::string store;
    IfcOptions ifc;
    bool noGlazing = false;
    std::string cells = "given";
  };
  auto o = std::make_shared<Options>();
  auto* import = scene.add_subcommand("import", "import a building.json, or mesh files, into a scene store");
  import->add_option("--grid", o->import.gridResolution,
                     "cut the scene into RGxRGxRG uniform voxel cells instead of its own cells (0: off)")
      ->capture_default_str()
      ->check(CLI::Range(0u, portico::kMaxImportGridResolution));
  import->add_option("--cells", o->cells,
                     "the cells: the input's own (given: a building.json's, else one cell), or rooms and portals "
                     "found in the geometry (rooms: for meshes with no topology, docs/room-finding.md; an IFC model without "
                     "usable IfcSpace gets rooms anyway)")
      ->capture_default_str()
      ->check(CLI::IsMember({"given", "rooms"}));
  import->add_option("--voxel-size", o->import.rooms.voxelSize,
                     "--cells rooms: the voxel edge of the room search, in scene units (metres); grown on very "
                     "large meshes to bound memory")
      ->capture_default_str()
      ->check(CLI::Range(0.01f, 10.0f));
  import->add_option("--opening-width", o->import.rooms.openingWidth,
                     "--cells rooms: free space narrower than this (doors, windows, stair openings) separates rooms")
      ->capture_default_str()
      ->check(CLI::Range(0.1f, 100.0f));
  import->add_option("--camera", o->import.camera,
                     "the store's default camera: the building.json's camera of this name (default: the first; every "
                     "camera is stored, for render --camera NAME)");
  import->add_option("--lights", o->ifc.lights,
                     "IFC input: lamps from the model's light fixtures (fixtures), one ceiling panel per space (panels), "
                     "or fixtures where the model has some, else panels (auto), or no lamps, for daylight (none)")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "fixtures", "panels", "none"}));
  import->add_flag("--no-glazing", o->noGlazing,
                   "IFC input: leave windows out, their holes open (default: their glass becomes thin glass panes)");
  import->add_option("--outdoors", o->ifc.outdoors,
                     "IFC input: the air around the building is outdoors, for daylight (open), or closed by a black "
                     "sky and a grey ground (closed)")
      ->capture_default_str()
      ->check(CLI::IsMember({"open", "closed"}));
  import->add_option("--keep-conversion", o->ifc.keepConversion,
                     "IFC input: keep the converter's building.json, meshes and conversion.json (with the rooms "
                     "found, for python -m portico_ifc.watertight) in this directory");
  import->add_option("INPUT", o->inputs, "building.json, an IFC model (.ifc), or mesh files (OBJ, PLY, glTF/GLB, ...)")
      ->required();
  import->add_option("STORE", o->store, "scene store directory to write")->required();
  import->positionals_at_end();   // INPUT... takes all but the last positional, STORE the last
  table.add(import, [o] {
    o->ifc.glazing = !o->noGlazing;
    o->import.findRooms = o->cells == "rooms";
    return runSceneImport(o->inputs, o->import, o->store, o->ifc);
  });
}

void addInfo(CLI::App& scene, CommandTable& table) {
  struct Options {
    std::string store;
    bool json = false;
    bool noCompress = false;
    bool quick = false;
  };
  auto o = std::make_shared<Options>();
  auto* info = scene.add_subcommand("info", "describe a scene store");
  info->add_option("STORE", o->store, "scene store directory")->required()->check(CLI::ExistingDirectory);
  info->add_flag("--json", o->json, "one JSON object on stdout");
  info->add_flag("--no-compress", o->noCompress, "skip the zlib-compressed size (slow on large stores)");
  info->add_flag("--quick", o->quick,
                 "read no cell file: no compressed size, and cell files checked by their size only (seconds on "
                 "the 101-floor tower's 25 GB)");
  table.add(info, [o] {
    return runSceneInfo(o->store, SceneInfoOptions{o->json, !o->noCompress && !o->quick, !o->quick});
  });
}

void addExport(CLI::App& scene, CommandTable& table) {
  struct Options {
    std::string store, output;
    DaylightSettings daylight;
  };
  auto o = std::make_shared<Options>();
  auto* exportCommand =
      scene.add_subcommand("export", "write a scene store as glTF (.glb, .gltf), OBJ + MTL, or a Radiance scene (.rad)");
  exportCommand->add_option("STORE", o->store, "scene store directory")->required()->check(CLI::ExistingDirectory);
  exportCommand
      ->add_option("-o,--output", o->output,
                   "file to write: FILE.glb, FILE.gltf (FILE.bin beside it), FILE.obj (FILE.mtl beside it) or FILE.rad "
                   "(Radiance; with --sky/--sun, the daylight as FILE.sky.rad beside it)")
      ->required();
  // Render's daylight options, for the Radiance export's sky file.
  addDaylightOptions(*exportCommand, o->daylight);
  table.add(exportCommand, [o] { return runSceneExport(o->store, o->output, o->daylight); });
}

void addPlan(CLI::App& scene, CommandTable& table) {
  struct Options {
    std::string store;
    ScenePlanOptions plan;
  };
  auto o = std::make_shared<Options>();
  auto* plan = scene.add_subcommand("plan", "draw top-down floor plans of a scene store as a PNG");
  plan->add_option("STORE", o->store, "scene store directory")->required()->check(CLI::ExistingDirectory);
  plan->add_option("-o,--output", o->plan.output, "PNG file to write")->required();
  plan->add_option("--floor", o->plan.floor, "draw only this floor (0 = lowest)")->check(CLI::NonNegativeNumber);
  plan->add_option("--size", o->plan.panelSize, "pixels along the longer side of each floor's panel")
      ->capture_default_str()
      ->check(CLI::Range(64, 8192));
  table.add(plan, [o] { return runScenePlan(o->store, o->plan); });
}

void addGrid(CLI::App& scene, CommandTable& table) {
  struct Options {
    std::string store, output;
    WorkPlaneGridOptions grid;
    bool verbose = false;
  };
  auto o = std::make_shared<Options>();
  auto* grid = scene.add_subcommand(
      "grid", "write the work-plane grid of `analyze --grid auto` as a Radiance .pts file, without measuring it");
  grid->add_option("STORE", o->store, "scene store directory")->required()->check(CLI::ExistingDirectory);
  grid->add_option("-o,--output", o->output, ".pts file to write: one `x y z dx dy dz` line per point")->required();
  addWorkPlaneGridOptions(*grid, o->grid);
  grid->add_flag("--rooms", o->verbose, "list every room: its cell, floor, floor area and points");
  table.add(grid, [o] { return runSceneGrid(o->store, o->output, o->grid, o->verbose); });
}

}  // namespace

void addIes(CLI::App& scene, CommandTable& table) {
  auto files = std::make_shared<std::vector<std::string>>();
  auto* ies = scene.add_subcommand("ies", "read IES LM-63 photometric files and print each one's total lumens");
  ies->add_option("FILE", *files, "IES files (.ies)")->required();
  table.add(ies, [files] { return runSceneIes(*files); });
}

void addSceneCommands(CLI::App& app, CommandTable& table) {
  auto* scene = app.add_subcommand("scene", "create and inspect scene stores");
  scene->require_subcommand(1);
  addGenerate(*scene, table);
  addImport(*scene, table);
  addInfo(*scene, table);
  addExport(*scene, table);
  addPlan(*scene, table);
  addGrid(*scene, table);
  addIes(*scene, table);
}

}  // namespace portico::cli
