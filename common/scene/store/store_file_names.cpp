#include "common/scene/store/store_file_names.h"

#include <fmt/format.h>
#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <vector>

#include "common/scene/store/scene_store.h"

namespace portico {

namespace {
// "<prefix><digits><suffix>", 1 to 10 digits.
bool isNumberedFile(const std::string& path, const std::string& prefix, const std::string& suffix) {
  if (path.size() <= prefix.size() + suffix.size() || path.compare(0, prefix.size(), prefix) != 0 ||
      path.compare(path.size() - suffix.size(), suffix.size(), suffix) != 0)
    return false;
  const std::string digits = path.substr(prefix.size(), path.size() - prefix.size() - suffix.size());
  return digits.size() <= 10 && std::all_of(digits.begin(), digits.end(), [](char c) { return std::isdigit(uint8_t(c)); });
}
}  // namespace

bool isServableStorePath(const std::string& path) {
  return path == "scene.db" || isNumberedFile(path, "cells/", ".cell") || isNumberedFile(path, "textures/", ".tif");
}

void requireRegularStoreFiles(const SceneStore& store) {
  std::vector<std::string> files;
  for (const CellInfo& cell : store.cells()) files.push_back(cell.file);
  for (const Material& material : store.materials())
    if (material.textured()) files.push_back(material.albedoTexture);
  for (const std::string& file : files) {
    struct stat info {};
    const std::string path = (std::filesystem::path(store.directory()) / file).string();
    if (::stat(path.c_str(), &info) == 0 && !S_ISREG(info.st_mode))
      throw std::runtime_error(fmt::format("scene store {}: {} is not a regular file{}", store.directory(), file,
                                           S_ISFIFO(info.st_mode) ? " (a FIFO)" : ""));
  }
}

}  // namespace portico
