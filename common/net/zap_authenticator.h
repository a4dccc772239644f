// A ZeroMQ authentication handler (ZAP, RFC 27) for CURVE servers: a thread
// answering libzmq's requests on inproc://zeromq.zap.01, accepting the
// client keys it was given (status 200) and refusing every other (400).
// Construct it before binding a CURVE server socket of the same context:
// with no handler bound, libzmq lets any key in.
#pragma once

#include <atomic>
#include <set>
#include <string>
#include <thread>
#include <zmq.hpp>

#include "common/net/curve_keys.h"
#include "common/util/log_throttle.h"

namespace portico::net {

class ZapAuthenticator {
 public:
  ZapAuthenticator(zmq::context_t& context, const ServerKeys& keys);
  ~ZapAuthenticator();   // stops the thread; destroy it before the context
  ZapAuthenticator(const ZapAuthenticator&) = delete;
  ZapAuthenticator& operator=(const ZapAuthenticator&) = delete;

 private:
  void serve();
  void answer(const std::vector<zmq::message_t>& request);
  void logRefusal(const std::string& key, const std::string& address, const std::string& why);

  zmq::socket_t socket_;
  std::set<std::string> authorized_;   // Z85
  std::string authorizedFile_;
  // A refused peer retries every reconnect interval: one line per key a minute.
  LogThrottle refusals_;
  std::atomic<bool> stopping_{false};
  std::thread thread_;
};

}  // namespace portico::net
