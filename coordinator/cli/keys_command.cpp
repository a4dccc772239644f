// `portico keys generate DIR`: the CURVE keys of a coordinator and of the
// three roles that reach it (client, worker, operator), each its own pair.
#include <fmt/format.h>

#include <filesystem>
#include <iostream>
#include <memory>

#include "common/net/curve_keys.h"
#include "coordinator/cli/command_table.h"
#include "coordinator/cli/commands.h"

namespace portico::cli {

int runKeysGenerate(const std::string& directory) {
  const std::vector<std::string> written = net::generateKeys(directory);
  const std::string dir = std::filesystem::absolute(directory).lexically_normal().string();
  std::string pairs;
  for (const std::string& name : written) pairs += (pairs.empty() ? "" : ", ") + name;
  std::cout << fmt::format(
      "{1} in {0}\n"
      "coordinator: portico-coordinator --keys DIR (needs coordinator.secret and client.public, worker.public, "
      "operator.public)\n"
      "workers:     portico-worker --keys DIR (need coordinator.public, worker.secret)\n"
      "clients:     portico submit|status|wait|cancel|fetch-image --keys DIR (need coordinator.public, client.secret)\n"
      "operators:   portico shutdown --keys DIR (needs coordinator.public, operator.secret)\n",
      dir, written.empty() ? std::string("every key pair was already there") : "wrote the key pairs " + pairs);
  return 0;
}

void addKeysCommands(CLI::App& app, CommandTable& table) {
  auto directory = std::make_shared<std::string>();
  auto* keys = app.add_subcommand("keys", "ZeroMQ CURVE keys for services listening beyond loopback");
  keys->require_subcommand(1);
  auto* keysGenerate = keys->add_subcommand(
      "generate", "write the key pairs DIR lacks: coordinator, client, worker and operator .{public,secret} (Z85; "
                  "secrets mode 0600; existing keys are kept)");
  keysGenerate->add_option("DIR", *directory, "directory to write the key files into")->required();
  table.add(keysGenerate, [directory] { return runKeysGenerate(*directory); });
}

}  // namespace portico::cli
