// `portico keys generate DIR`: the CURVE keys of a coordinator and of the
// three roles that reach it (client, worker, operator), each its own pair.
#include <fmt/format.h>

#include <filesystem>
#include <iostream>

#include "common/net/curve_keys.h"
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

}  // namespace portico::cli
