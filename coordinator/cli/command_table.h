// What `portico` runs once its command line is parsed. Each subcommand that
// does something is registered with its action; the options it fills are
// owned by the action (shared_ptr), so they outlive the registration
// function that bound them to the command line.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <utility>
#include <vector>

namespace portico::cli {

class CommandTable {
 public:
  void add(CLI::App* command, std::function<int()> action) { entries_.push_back({command, std::move(action)}); }
  // The exit status of the action of the subcommand the command line named
  // (0 when it named none that acts).
  int runParsed() const {
    for (const Entry& entry : entries_)
      if (*entry.command) return entry.action();
    return 0;
  }

 private:
  struct Entry {
    CLI::App* command;
    std::function<int()> action;
  };
  std::vector<Entry> entries_;
};

}  // namespace portico::cli
