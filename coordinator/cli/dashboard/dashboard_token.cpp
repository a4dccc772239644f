#include "coordinator/cli/dashboard/dashboard_token.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "common/util/trusted_path.h"

namespace portico::cli {

namespace fs = std::filesystem;

namespace {
constexpr size_t kTokenBytes = 32;

std::string randomToken() {
  unsigned char bytes[kTokenBytes];
  size_t got = 0;
  while (got < sizeof bytes) {
    const ssize_t n = ::getrandom(bytes + got, sizeof bytes - got, 0);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw std::runtime_error(fmt::format("cannot draw a random dashboard token: {}", std::strerror(errno)));
    got += size_t(n);
  }
  std::string hex;
  for (unsigned char b : bytes) hex += fmt::format("{:02x}", b);
  return hex;
}

bool isToken(const std::string& text) {
  return text.size() == 2 * kTokenBytes && text.find_first_not_of("0123456789abcdef") == std::string::npos;
}

// Written beside it with the mode set at creation (never readable by
// others, not even for a moment) and renamed over it.
void writeToken(const fs::path& path, const std::string& token) {
  const fs::path temporary = path.string() + ".new";
  ::unlink(temporary.c_str());
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, 0600);
  if (fd < 0) throw std::runtime_error(fmt::format("dashboard token file {}: cannot create: {}", temporary.string(), std::strerror(errno)));
  const std::string text = token + "\n";
  const bool written = ::write(fd, text.data(), text.size()) == ssize_t(text.size());
  ::close(fd);
  if (!written || ::rename(temporary.c_str(), path.c_str()) != 0)
    throw std::runtime_error(fmt::format("dashboard token file {}: cannot write: {}", path.string(), std::strerror(errno)));
}
}  // namespace

std::string defaultDashboardTokenPath() {
  if (const char* config = std::getenv("XDG_CONFIG_HOME"); config && *config)
    return (fs::path(config) / "portico" / "dashboard" / "token").string();
  if (const char* home = std::getenv("HOME"); home && *home)
    return (fs::path(home) / ".config" / "portico" / "dashboard" / "token").string();
  return "";
}

std::string loadOrCreateDashboardToken(const std::string& pathText, bool renew) {
  if (pathText.empty())
    throw std::runtime_error("the dashboard keeps its token in the user's config folder, but neither XDG_CONFIG_HOME "
                             "nor HOME is set: give --token-file FILE");
  const fs::path path(pathText), folder = fs::path(pathText).parent_path();
  if (!folder.empty() && !fs::exists(folder)) {
    fs::create_directories(folder.parent_path());
    if (::mkdir(folder.c_str(), 0700) != 0 && errno != EEXIST)
      throw std::runtime_error(fmt::format("dashboard token directory {}: cannot create: {}", folder.string(), std::strerror(errno)));
  }
  if (!folder.empty()) requireTrustedPath(folder, true, "dashboard token");
  requireTrustedPath(path, false, "dashboard token");
  struct stat info {};
  if (!renew && ::lstat(path.c_str(), &info) == 0) {
    if (!S_ISREG(info.st_mode))
      throw std::runtime_error(fmt::format("dashboard token file {}: not a regular file", path.string()));
    // Readable by others, it is no secret: refused rather than used (ssh does the same with keys).
    if (info.st_mode & 077)
      throw std::runtime_error(fmt::format("dashboard token file {}: readable by other users (mode {:o}); chmod 600 "
                                           "it, or start with --new-token",
                                           path.string(), info.st_mode & 0777));
    std::ifstream in(path);
    std::string token;
    std::getline(in, token);
    if (!isToken(token))
      throw std::runtime_error(fmt::format("dashboard token file {}: not {} hex digits; start with --new-token to "
                                           "replace it",
                                           path.string(), 2 * kTokenBytes));
    return token;
  }
  const std::string token = randomToken();
  writeToken(path, token);
  return token;
}

bool sameToken(std::string_view given, std::string_view token) {
  unsigned char difference = given.size() == token.size() ? 0 : 1;
  for (size_t i = 0; i < token.size(); ++i) difference |= (i < given.size() ? given[i] : 0) ^ token[i];
  return difference == 0;
}

}  // namespace portico::cli
