// `portico bench accel|quality|pipeline|paper|calibrate`: the benchmarks'
// options and actions (bench_command_line.cpp).
#pragma once

#include <CLI/CLI.hpp>

namespace portico::cli {

class CommandTable;
void addBenchCommands(CLI::App& app, CommandTable& table);

}  // namespace portico::cli
