// ZeroMQ CURVE keys: written by `portico keys generate DIR`, read by every
// program given `--keys DIR`. Z85 text files, one key a line ('#' starts a
// comment): the coordinator's pair, and one pair per role (net/role.h):
//   coordinator.public   the coordinator's public key (everyone pins it)
//   coordinator.secret   the coordinator's secret key (mode 0600)
//   ROLE.public          the keys the coordinator admits as ROLE, one a line
//   ROLE.secret          the secret key a ROLE presents (mode 0600)
// with ROLE client (submit, status, cancel), worker (lease, results, its
// leases' files) and operator (everything, shutdown included). The first
// line of ROLE.public is the public half of ROLE.secret; add more lines to
// admit other key pairs in that role.
#pragma once

#include <map>
#include <string>
#include <vector>
#include <zmq.hpp>

#include "common/net/role.h"

namespace portico::net {

struct CurveKeyPair {
  std::string publicKey;   // Z85, 40 characters
  std::string secretKey;
};

// What a coordinator needs: its own pair and the keys it admits, each in one role.
struct ServerKeys {
  CurveKeyPair server;
  std::map<std::string, Role> authorized;   // Z85 public key -> its role
  std::string directory;                    // where they came from, for log lines
};

// What a worker or client needs: the coordinator's public key and its own pair.
struct ClientKeys {
  std::string serverPublicKey;
  CurveKeyPair client;
};

// Writes the key pairs `directory` lacks (created mode 0700 if missing):
// the coordinator's and one per role. Never overwrites a key; a pair with
// one half missing is an error. Returns the pairs written ("client", ...).
// Throws std::runtime_error naming the file.
std::vector<std::string> generateKeys(const std::string& directory);

// Read and check the files (Z85, 40 characters, secret and public halves
// matching). Throw std::runtime_error naming the file and the problem.
// A missing ROLE.public admits no key in that role (a warning is logged).
// As ssh does, keys another user could have put there are refused: the
// directory and its files must be owned by this user or root and writable
// by no one else, and the folders above it writable by others only when
// sticky.
ServerKeys loadServerKeys(const std::string& directory);
// The coordinator's public key and `role`'s pair (ROLE.secret).
ClientKeys loadClientKeys(const std::string& directory, Role role);

// The per-user keys directory: $PORTICO_KEYS, else
// $XDG_CONFIG_HOME/portico/keys, else ~/.config/portico/keys ("" when
// neither HOME nor those are set).
std::string defaultKeysDirectory();
// The per-user directory, its keys generated (mode 0700, atomically, so two
// coordinators starting at once agree) when missing. Throws naming it.
std::string ensureDefaultKeys();
// The keys a worker or client uses towards `endpoint`: `given`, else the
// per-user directory when the endpoint is tcp:// and that directory holds a
// coordinator.public (a coordinator started without --keys on tcp:// uses
// it), else "" (no CURVE: ipc:// and inproc://). On tcp:// with neither it
// throws: a coordinator on tcp:// always has a CURVE key, so a peer that
// does not know it could only be talking to an impostor.
std::string keysForEndpoint(const std::string& given, const std::string& endpoint);

// Socket options: a CURVE server (call before bind, with a ZAP handler
// already bound, or libzmq accepts every key), or a client pinned to the server's key.
void applyServerKeys(zmq::socket_t& socket, const ServerKeys& keys);
void applyClientKeys(zmq::socket_t& socket, const ClientKeys& keys);

// The Z85 text of a 32-byte binary key (ZAP hands keys over in binary).
std::string z85FromBinaryKey(const void* key, size_t bytes);

}  // namespace portico::net
