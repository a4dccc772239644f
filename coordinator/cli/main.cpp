// portico: the user's command. Generates and inspects scene stores, renders
// locally (its own coordinator and workers), talks to running services, and
// measures portico's parts (bench/).
#include <CLI/CLI.hpp>

#include <exception>
#include <iostream>

#include "coordinator/cli/bench/bench_command_line.h"
#include "coordinator/cli/command_table.h"
#include "coordinator/cli/commands.h"

int main(int argc, char** argv) {
  using namespace portico::cli;
  CLI::App app{"portico: photon mapping for very large buildings, cell by cell"};
  app.require_subcommand(1);
  CommandTable commands;
  addSceneCommands(app, commands);
  addJobCommands(app, commands);
  addKeysCommands(app, commands);
  addBenchCommands(app, commands);

  CLI11_PARSE(app, argc, argv);
  try {
    return commands.runParsed();
  } catch (const std::exception& e) {
    std::cerr << "portico: " << e.what() << "\n";
    return 1;
  }
}
