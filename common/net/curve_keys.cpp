#include "common/net/curve_keys.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace portico::net {

namespace fs = std::filesystem;

namespace {

constexpr size_t kZ85KeyLength = 40;
const char* const kCoordinatorPublic = "coordinator.public";
const char* const kCoordinatorSecret = "coordinator.secret";
const char* const kClientPublic = "client.public";
const char* const kClientSecret = "client.secret";

bool isZ85Key(const std::string& text) {
  if (text.size() != kZ85KeyLength) return false;
  uint8_t binary[32];
  return zmq_z85_decode(binary, text.c_str()) != nullptr;
}

// Every key in the file, in order; comments and blank lines skipped.
std::vector<std::string> readKeys(const fs::path& path) {
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

void generateKeys(const std::string& directory) {
  const fs::path dir(directory);
  fs::create_directories(dir);
  for (const char* name : {kCoordinatorPublic, kCoordinatorSecret, kClientPublic, kClientSecret})
    if (fs::exists(dir / name))
      throw std::runtime_error(
          fmt::format("key file {}: already exists (keys are never overwritten; remove it first)", (dir / name).string()));
  char serverPublic[kZ85KeyLength + 1], serverSecret[kZ85KeyLength + 1];
  char clientPublic[kZ85KeyLength + 1], clientSecret[kZ85KeyLength + 1];
  if (zmq_curve_keypair(serverPublic, serverSecret) != 0 || zmq_curve_keypair(clientPublic, clientSecret) != 0)
    throw std::runtime_error(fmt::format("cannot generate CURVE keys: {} (libzmq built without CURVE?)",
                                         zmq_strerror(zmq_errno())));
  writeKeyFile(dir / kCoordinatorSecret, "portico coordinator secret key (CURVE, Z85): keep it on the coordinator",
               serverSecret, 0600);
  writeKeyFile(dir / kCoordinatorPublic, "portico coordinator public key (CURVE, Z85): give it to workers and clients",
               serverPublic, 0644);
  writeKeyFile(dir / kClientSecret, "portico client secret key (CURVE, Z85): workers and clients use it",
               clientSecret, 0600);
  writeKeyFile(dir / kClientPublic,
               "client public keys the coordinator accepts (CURVE, Z85), one a line", clientPublic, 0644);
}

ServerKeys loadServerKeys(const std::string& directory) {
  const fs::path dir(directory);
  ServerKeys keys;
  keys.server = readPair(dir / kCoordinatorSecret);
  // A coordinator.public that does not match would leave every worker
  // waiting on a handshake that cannot succeed: refuse to start instead.
  if (fs::exists(dir / kCoordinatorPublic) && readOneKey(dir / kCoordinatorPublic) != keys.server.publicKey)
    throw std::runtime_error(fmt::format("key file {}: is not the public half of {}",
                                         (dir / kCoordinatorPublic).string(), (dir / kCoordinatorSecret).string()));
  keys.authorizedFile = (dir / kClientPublic).string();
  keys.authorizedClients = readKeys(dir / kClientPublic);
  return keys;
}

ClientKeys loadClientKeys(const std::string& directory) {
  const fs::path dir(directory);
  ClientKeys keys;
  keys.serverPublicKey = readOneKey(dir / kCoordinatorPublic);
  keys.client = readPair(dir / kClientSecret);
  return keys;
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
