// `portico dashboard`'s web server (cpp-httplib): the page, its event
// stream, previews, plans and the actions, every request behind the token.
//
// Security (docs/dashboard.md):
//  * it listens on loopback only: the page is plain HTTP, so the token must
//    not cross a network (reach it from elsewhere through an ssh tunnel);
//  * every request carries the token: the cookie set by opening the printed
//    URL (/?token=...; HttpOnly, SameSite=Strict), or an X-Portico-Token
//    header. Without one: 401; a wrong one: 403;
//  * actions (POST) need the header itself, and an Origin, when sent, of
//    this server: a page of another site can neither read the token nor
//    send the header without a CORS preflight, which is never granted;
//  * a Host header other than this server's names is refused (DNS rebinding);
//  * the page shows what the coordinator's Status tells the dashboard's
//    client key, and acts with that key: nothing `portico status` and
//    `portico cancel` and `portico priority` would not.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "coordinator/cli/commands.h"
#include "coordinator/cli/dashboard/farm_poller.h"

namespace portico::cli {

struct DashboardListen {
  std::string host = "127.0.0.1";
  int port = 8080;   // 0: any free port
};

// "HOST:PORT" ("[::1]:8080"); throws std::invalid_argument in one line
// naming --listen when HOST is not a loopback address or PORT no port.
DashboardListen parseDashboardListen(const std::string& text);

class DashboardServer {
 public:
  DashboardServer(const ConnectOptions& connect, FarmPoller& poller, std::string token);
  ~DashboardServer();
  // Binds; returns the port bound (the given one, or the one picked for 0).
  // Throws std::runtime_error naming the address when it cannot bind.
  int bind(const DashboardListen& listen);
  void serve();   // until stop()
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace portico::cli
