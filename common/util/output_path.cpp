#include "common/util/output_path.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <climits>
#include <filesystem>
#include <stdexcept>
#include <string_view>

namespace portico {

namespace {
// What common/image/image_writer.h writes: linear formats and 8-bit ones.
constexpr std::array<std::string_view, 7> kImageExtensions{".png", ".exr", ".hdr", ".tif", ".tiff", ".jpg", ".jpeg"};
}  // namespace

void checkOutputPath(const std::string& path, OutputKind kind) {
  namespace fs = std::filesystem;
  const fs::path output(path);
  std::string extension = output.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) { return std::tolower(c); });
  std::error_code error;
  if (fs::is_directory(output, error))
    throw std::invalid_argument(fmt::format("output {}: is a directory (give a file name ending in .png or .exr)", path));
  if (kind == OutputKind::AnalysisCsv) {
    if (extension != ".csv")
      throw std::invalid_argument(fmt::format("output {}: an analysis writes CSV: give a file name ending in .csv", path));
  } else if (std::find(kImageExtensions.begin(), kImageExtensions.end(), extension) == kImageExtensions.end())
    throw std::invalid_argument(fmt::format("output {}: {} (use .png, .exr, .hdr, .tif or .jpg)", path,
                                            extension.empty() ? std::string("has no image extension")
                                                              : fmt::format("unknown image extension {}", extension)));
  const fs::path parent = output.has_parent_path() ? output.parent_path() : fs::path(".");
  // Beside the image go OUTPUT.json, each written as a temporary of a longer
  // name first (".tmp-" + name, OUTPUT.json.tmp): the longest of them must fit.
  constexpr size_t kLongestSuffix = std::string_view(".json.tmp").size();
  const long nameMax = ::pathconf(parent.c_str(), _PC_NAME_MAX);
  const size_t mostName = (nameMax > 0 ? size_t(nameMax) : size_t(NAME_MAX)) - kLongestSuffix;
  if (output.filename().string().size() > mostName)
    throw std::invalid_argument(fmt::format("output {}: its name is {} bytes; at most {} here (the file system's "
                                            "{}, less {} for the files written beside it)",
                                            path, output.filename().string().size(), mostName,
                                            nameMax > 0 ? nameMax : long(NAME_MAX), kLongestSuffix));
  if (path.size() + kLongestSuffix >= PATH_MAX)
    throw std::invalid_argument(fmt::format("output {}...: the path is {} bytes; at most {}", path.substr(0, 60),
                                            path.size(), PATH_MAX - 1 - kLongestSuffix));
  if (!fs::is_directory(parent, error))
    throw std::invalid_argument(fmt::format("output {}: directory {} does not exist (create it first)", path,
                                            parent.string()));
  // The image is written beside its name and renamed: the directory must be writable.
  if (::faccessat(AT_FDCWD, parent.c_str(), W_OK | X_OK, AT_EACCESS) != 0)
    throw std::invalid_argument(fmt::format("output {}: directory {} is not writable by uid {}", path, parent.string(),
                                            ::geteuid()));
}

}  // namespace portico
