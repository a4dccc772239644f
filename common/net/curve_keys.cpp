#include "common/net/curve_keys.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "common/util/trusted_path.h"

namespace portico::net {

namespace fs = std::filesystem;

namespace {

constexpr size_t kZ85KeyLength = 40;
const char* const kCoordinatorPublic = "coordinator.public";
const char* const kCoordinatorSecret = "coordinator.secret";

std::string publicFile(std::string_view pair) { return fmt::format("{}.public", pair); }
std::string secretFile(std::string_view pair) { return fmt::format("{}.secret", pair); }

bool isZ85Key(const std::string& text) {
  if (text.size() != kZ85KeyLength) return false;
  uint8_t binary[32];
  return zmq_z85_decode(binary, text.c_str()) != nullptr;
}

// Keys are trusted only where no other user could have put them
// (common/util/trusted_path.h).
void requireTrustedKeyPath(const fs::path& path, bool directory) { requireTrustedPath(path, directory, "key"); }

// Every key in the file, in order; comments and blank lines skipped.
std::vector<std::string> readKeys(const fs::path& path) {
  requireTrustedKeyPath(path, false);
  std::ifstream in(path);
  if (!in)
    throw std::runtime_error(fmt::format("key file {}: cannot open: {} (write keys with `portico keys generate {}`)",
                                         path.string(), std::strerror(errno), path.parent_path().string()));
  std::vector<std::string> keys;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const std::string key = line.substr(first, line.find_last_not_of(" \t\r") + 1 - first);
    if (!isZ85Key(key))
      throw std::runtime_error(fmt::format("key file {}: line {} is not a {}-character Z85 CURVE key", path.string(),
                                           number, kZ85KeyLength));
    keys.push_back(key);
  }
  if (keys.empty()) throw std::runtime_error(fmt::format("key file {}: holds no key", path.string()));
  return keys;
}

std::string readOneKey(const fs::path& path) {
  const auto keys = readKeys(path);
  if (keys.size() != 1)
    throw std::runtime_error(fmt::format("key file {}: holds {} keys, expected one", path.string(), keys.size()));
  return keys.front();
}

// A secret key readable by others is no longer secret; say so, as ssh does.
void warnIfExposed(const fs::path& path) {
  struct stat info {};
  if (::stat(path.c_str(), &info) == 0 && (info.st_mode & 077))
    spdlog::warn("key file {}: readable by other users (mode {:o}); chmod 600 it", path.string(),
                 info.st_mode & 0777);
}

// The pair of a secret key file, its public half derived from it.
CurveKeyPair readPair(const fs::path& secretPath) {
  CurveKeyPair pair;
  pair.secretKey = readOneKey(secretPath);
  warnIfExposed(secretPath);
  char derived[kZ85KeyLength + 1];
  if (zmq_curve_public(derived, pair.secretKey.c_str()) != 0)
    throw std::runtime_error(fmt::format("key file {}: cannot derive its public key: {}", secretPath.string(),
                                         zmq_strerror(zmq_errno())));
  pair.publicKey = derived;
  return pair;
}

void writeKeyFile(const fs::path& path, const std::string& comment, const std::string& key, mode_t mode) {
  // O_EXCL: never overwrite a key; the mode is set at creation, so a secret
  // is never readable by others, not even for a moment.
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, mode);
  if (fd < 0)
    throw std::runtime_error(fmt::format("key file {}: cannot create: {}{}", path.string(), std::strerror(errno),
                                         errno == EEXIST ? " (keys are never overwritten; remove it first)" : ""));
  const std::string text = fmt::format("# {}\n{}\n", comment, key);
  const bool written = ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  ::close(fd);
  if (!written) throw std::runtime_error(fmt::format("key file {}: cannot write: {}", path.string(), std::strerror(errno)));
}

}  // namespace

std::vector<std::string> generateKeys(const std::string& directory) {
  const fs::path dir(directory);
  if (!fs::exists(dir)) {
    fs::create_directories(dir);
    fs::permissions(dir, fs::perms::owner_all);   // secrets inside: others may not even list them
  }
  struct Pair {
    std::string name, holder;
  };
  std::vector<Pair> pairs{{"coordinator", "keep it on the coordinator"}};
  for (Role role : kAllRoles) pairs.push_back({std::string(roleName(role)), fmt::format("{}s use it", roleName(role))});
  std::vector<std::string> written;
  for (const Pair& pair : pairs) {
    const bool hasPublic = fs::exists(dir / publicFile(pair.name)), hasSecret = fs::exists(dir / secretFile(pair.name));
    if (hasPublic && hasSecret) continue;   // kept: keys are never overwritten
    if (hasPublic != hasSecret)
      throw std::runtime_error(fmt::format("key file {}: exists without its other half {} (keys are never overwritten; "
                                           "remove it first)",
                                           (dir / (hasPublic ? publicFile(pair.name) : secretFile(pair.name))).string(),
                                           hasPublic ? secretFile(pair.name) : publicFile(pair.name)));
    char publicKey[kZ85KeyLength + 1], secretKey[kZ85KeyLength + 1];
    if (zmq_curve_keypair(publicKey, secretKey) != 0)
      throw std::runtime_error(fmt::format("cannot generate CURVE keys: {} (libzmq built without CURVE?)",
                                           zmq_strerror(zmq_errno())));
    const bool coordinator = pair.name == "coordinator";
    writeKeyFile(dir / secretFile(pair.name),
                 fmt::format("portico {} secret key (CURVE, Z85): {}", pair.name, pair.holder), secretKey, 0600);
    writeKeyFile(dir / publicFile(pair.name),
                 coordinator ? "portico coordinator public key (CURVE, Z85): give it to workers, clients and operators"
                             : fmt::format("{} public keys the coordinator admits (CURVE, Z85), one a line", pair.name),
                 publicKey, 0644);
    written.push_back(pair.name);
  }
  return written;
}

ServerKeys loadServerKeys(const std::string& directory) {
  const fs::path dir(directory);
  requireTrustedKeyPath(dir, true);
  ServerKeys keys;
  keys.server = readPair(dir / kCoordinatorSecret);
  // A coordinator.public that does not match would leave every worker
  // waiting on a handshake that cannot succeed: refuse to start instead.
  if (fs::exists(dir / kCoordinatorPublic) && readOneKey(dir / kCoordinatorPublic) != keys.server.publicKey)
    throw std::runtime_error(fmt::format("key file {}: is not the public half of {}",
                                         (dir / kCoordinatorPublic).string(), (dir / kCoordinatorSecret).string()));
  keys.directory = dir.string();
  for (Role role : kAllRoles) {
    const fs::path file = dir / publicFile(roleName(role));
    if (!fs::exists(file)) {
      spdlog::warn("key file {}: missing, so no {} is admitted (`portico keys generate {}` adds it)", file.string(),
                   roleName(role), dir.string());
      continue;
    }
    for (const std::string& key : readKeys(file)) {
      // One key, one role: a key listed twice would leave its rights to file order.
      const auto [it, added] = keys.authorized.emplace(key, role);
      if (!added && it->second != role)
        throw std::runtime_error(fmt::format("key file {}: key {} is also listed in {}: give each role its own key pair",
                                             file.string(), key, publicFile(roleName(it->second))));
    }
  }
  if (keys.authorized.empty())
    throw std::runtime_error(fmt::format("key directory {}: admits no key (no client.public, worker.public or "
                                         "operator.public)",
                                         dir.string()));
  return keys;
}

ClientKeys loadClientKeys(const std::string& directory, Role role) {
  const fs::path dir(directory);
  requireTrustedKeyPath(dir, true);
  ClientKeys keys;
  keys.serverPublicKey = readOneKey(dir / kCoordinatorPublic);
  keys.client = readPair(dir / secretFile(roleName(role)));
  return keys;
}

std::string defaultKeysDirectory() {
  if (const char* given = std::getenv("PORTICO_KEYS"); given && *given) return given;
  if (const char* config = std::getenv("XDG_CONFIG_HOME"); config && *config)
    return (fs::path(config) / "portico" / "keys").string();
  if (const char* home = std::getenv("HOME"); home && *home)
    return (fs::path(home) / ".config" / "portico" / "keys").string();
  return "";
}

std::string ensureDefaultKeys() {
  const std::string directory = defaultKeysDirectory();
  if (directory.empty())
    throw std::runtime_error("without --keys a coordinator on tcp:// uses per-user keys, but neither PORTICO_KEYS, "
                             "XDG_CONFIG_HOME nor HOME is set: give --keys DIR, or listen on ipc://");
  const fs::path dir(directory);
  if (fs::exists(dir / kCoordinatorSecret)) return directory;
  // Written whole in a private temporary directory and renamed into place:
  // a coordinator starting at the same moment either renames first or
  // finds the finished directory.
  fs::create_directories(dir.parent_path());
  std::string pattern = (dir.parent_path() / ".keys-XXXXXX").string();
  if (!::mkdtemp(pattern.data()))
    throw std::runtime_error(fmt::format("cannot create a directory beside {}: {}", directory, std::strerror(errno)));
  try {
    generateKeys(pattern);
  } catch (...) {
    fs::remove_all(pattern);
    throw;
  }
  if (::rename(pattern.c_str(), dir.c_str()) != 0) {
    const int error = errno;
    fs::remove_all(pattern);
    if (!fs::exists(dir / kCoordinatorSecret))
      throw std::runtime_error(fmt::format("cannot create the key directory {}: {}", directory, std::strerror(error)));
  } else {
    spdlog::info("wrote per-user CURVE keys to {} (mode 0700)", directory);
  }
  return directory;
}

std::string keysForEndpoint(const std::string& given, const std::string& endpoint) {
  if (!given.empty() || endpoint.rfind("tcp://", 0) != 0) return given;
  const std::string directory = defaultKeysDirectory();
  std::error_code error;
  if (!directory.empty() && fs::exists(fs::path(directory) / kCoordinatorPublic, error)) return directory;
  throw std::runtime_error(fmt::format(
      "{}: no coordinator key to check it by: give --keys DIR (with its coordinator.public), or run as the "
      "coordinator's user, whose keys are at {}",
      endpoint, directory.empty() ? std::string("$PORTICO_KEYS or ~/.config/portico/keys") : directory));
}

void applyServerKeys(zmq::socket_t& socket, const ServerKeys& keys) {
  socket.set(zmq::sockopt::curve_server, 1);
  socket.set(zmq::sockopt::curve_secretkey, keys.server.secretKey);
  socket.set(zmq::sockopt::zap_domain, "portico");
}

void applyClientKeys(zmq::socket_t& socket, const ClientKeys& keys) {
  socket.set(zmq::sockopt::curve_serverkey, keys.serverPublicKey);
  socket.set(zmq::sockopt::curve_publickey, keys.client.publicKey);
  socket.set(zmq::sockopt::curve_secretkey, keys.client.secretKey);
}

std::string z85FromBinaryKey(const void* key, size_t bytes) {
  if (bytes != 32) return fmt::format("<{}-byte key>", bytes);
  char text[kZ85KeyLength + 1];
  zmq_z85_encode(text, static_cast<const uint8_t*>(key), bytes);
  return text;
}

}  // namespace portico::net
