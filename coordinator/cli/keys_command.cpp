// `portico keys generate DIR`: the CURVE keys a coordinator needs to listen
// beyond loopback, and the pair its workers and clients present.
#include <fmt/format.h>

#include <filesystem>
#include <iostream>

#include "common/net/curve_keys.h"
#include "coordinator/cli/commands.h"

namespace portico::cli {

int runKeysGenerate(const std::string& directory) {
  net::generateKeys(directory);
  const std::string dir = std::filesystem::absolute(directory).lexically_normal().string();
  std::cout << fmt::format(
      "wrote {0}/coordinator.public, coordinator.secret, client.public, client.secret\n"
      "coordinator: portico-coordinator --keys {0} (needs coordinator.secret, client.public)\n"
      "workers and clients: --keys {0} (need coordinator.public, client.secret)\n",
      dir);
  return 0;
}

}  // namespace portico::cli
