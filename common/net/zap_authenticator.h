// A ZeroMQ authentication handler (ZAP, RFC 27): a thread answering
// libzmq's requests on inproc://zeromq.zap.01. For a CURVE server it admits
// the keys it was given (status 200, User-Id: the key's role and the key,
// net::zapUserId) and refuses
// every other (400). For an ipc:// socket without keys (NULL mechanism) it
// admits the peers whose uid (libzmq appends ":uid:gid:pid", read with
// SO_PEERCRED, to an ipc peer's address) is the server's own or root's, as
// operators, and refuses every other uid. Construct it before binding the
// server socket of the same context: with no handler bound, libzmq lets
// any key in.
#pragma once

#include <sys/types.h>

#include <atomic>
#include <map>
#include <optional>
#include <string>
#include <thread>
#include <zmq.hpp>

#include "common/net/curve_keys.h"
#include "common/util/log_throttle.h"

namespace portico::net {

class ZapAuthenticator {
 public:
  // CURVE: the keys' roles.
  ZapAuthenticator(zmq::context_t& context, const ServerKeys& keys);
  // NULL mechanism on ipc://: peers of uid `owner` or 0 are operators.
  ZapAuthenticator(zmq::context_t& context, uid_t owner);
  ~ZapAuthenticator();   // stops the thread; destroy it before the context
  ZapAuthenticator(const ZapAuthenticator&) = delete;
  ZapAuthenticator& operator=(const ZapAuthenticator&) = delete;

 private:
  explicit ZapAuthenticator(zmq::context_t& context);
  void serve();
  void answer(const std::vector<zmq::message_t>& request);
  // The role of an admitted peer, or why it is refused (in `why`).
  std::optional<Role> admitCurve(const std::string& key, std::string& why) const;
  std::optional<Role> admitByUid(const std::string& address, std::string& why) const;
  void logRefusal(const std::string& key, const std::string& address, const std::string& why);

  zmq::socket_t socket_;
  std::map<std::string, Role> authorized_;   // CURVE: Z85 key -> role
  std::string keysDirectory_;
  std::optional<uid_t> owner_;               // NULL mechanism on ipc://: the server's uid
  // A refused peer retries every reconnect interval: one line per key a minute.
  LogThrottle refusals_;
  std::atomic<bool> stopping_{false};
  std::thread thread_;
};

}  // namespace portico::net
