// ZeroMQ CURVE keys: written by `portico keys generate DIR`, read by every
// program given `--keys DIR`. Four Z85 text files, one key a line ('#'
// starts a comment):
//   coordinator.public   the coordinator's public key (workers and clients pin it)
//   coordinator.secret   the coordinator's secret key (mode 0600)
//   client.public        the client keys the coordinator accepts, one a line
//   client.secret        the secret key workers and clients use (mode 0600)
// The first line of client.public is the public half of client.secret; add
// more lines to authorize other key pairs.
#pragma once

#include <string>
#include <vector>
#include <zmq.hpp>

namespace portico::net {

struct CurveKeyPair {
  std::string publicKey;   // Z85, 40 characters
  std::string secretKey;
};

// What a coordinator needs: its own pair and the client keys it accepts.
struct ServerKeys {
  CurveKeyPair server;
  std::vector<std::string> authorizedClients;   // Z85
  std::string authorizedFile;                   // where they came from, for log lines
};

// What a worker or client needs: the coordinator's public key and its own pair.
struct ClientKeys {
  std::string serverPublicKey;
  CurveKeyPair client;
};

// Writes the four files into `directory` (created if missing). Refuses to
// overwrite an existing key file. Throws std::runtime_error naming the file.
void generateKeys(const std::string& directory);

// Read and check the files (Z85, 40 characters, secret and public halves
// matching). Throw std::runtime_error naming the file and the problem.
ServerKeys loadServerKeys(const std::string& directory);
ClientKeys loadClientKeys(const std::string& directory);

// Socket options: a CURVE server (call before bind, with a ZAP handler
// already bound, or libzmq accepts every key), or a client pinned to the server's key.
void applyServerKeys(zmq::socket_t& socket, const ServerKeys& keys);
void applyClientKeys(zmq::socket_t& socket, const ClientKeys& keys);

// The Z85 text of a 32-byte binary key (ZAP hands keys over in binary).
std::string z85FromBinaryKey(const void* key, size_t bytes);

}  // namespace portico::net
