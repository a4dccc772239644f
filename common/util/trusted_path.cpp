#include "common/util/trusted_path.h"

#include <fmt/format.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <stdexcept>
#include <string>

namespace portico {

namespace fs = std::filesystem;

namespace {
// Otherwise a user who made the folder beforehand would hold what it holds:
// the keys of every role (an operator's included) of our coordinator, or
// the token of our dashboard.
void requireOwnedByUs(const fs::path& path, const struct stat& info, const std::string& what, std::string_view thing) {
  const uid_t us = ::geteuid();
  if (info.st_uid != us && info.st_uid != 0)
    throw std::runtime_error(fmt::format("{} {}: owned by uid {}, not by uid {} (this user) or root: refusing {}s "
                                         "another user could have put there; remove it, or chown it",
                                         what, path.string(), info.st_uid, us, thing));
}
}  // namespace

void requireTrustedPath(const fs::path& path, bool directory, std::string_view thing) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0) return;
  const std::string what = fmt::format("{} {}", thing, directory ? "directory" : "file");
  requireOwnedByUs(path, info, what, thing);
  // On a read-only mount (a Kubernetes Secret volume, mode 1777) no one can write, whatever the mode says.
  struct statvfs mount {};
  const bool readOnly = ::statvfs(path.c_str(), &mount) == 0 && (mount.f_flag & ST_RDONLY);
  if (!readOnly && (info.st_mode & (S_IWGRP | S_IWOTH)))
    throw std::runtime_error(fmt::format("{} {}: writable by other users (mode {:o}): refusing it; chmod go-w it",
                                         what, path.string(), info.st_mode & 07777));
  if (!directory) return;
  std::error_code error;
  const fs::path resolved = fs::canonical(path, error);
  if (error) return;
  for (fs::path above = resolved.parent_path();; above = above.parent_path()) {
    if (::stat(above.c_str(), &info) == 0) {
      requireOwnedByUs(above, info, fmt::format("folder above the {}", what), thing);
      if ((info.st_mode & (S_IWGRP | S_IWOTH)) && !(info.st_mode & S_ISVTX))
        throw std::runtime_error(fmt::format("folder above the {} {}: writable by other users (mode {:o}), "
                                             "who could swap the {}s: refusing it",
                                             what, above.string(), info.st_mode & 07777, thing));
    }
    if (above == above.root_path() || above.empty()) break;
  }
}

}  // namespace portico
