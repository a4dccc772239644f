// `portico dashboard --coordinator ADDR [--listen 127.0.0.1:8080]`: the
// farm in a web page (docs/dashboard.md). A client of the coordinator like
// `portico status`, polling it from one thread (farm_poller.h) for every
// viewer; the page and its security are dashboard_server.h's.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <csignal>
#include <iostream>
#include <memory>
#include <thread>

#include "common/util/cli_bounds.h"
#include "coordinator/cli/command_table.h"
#include "coordinator/cli/commands.h"
#include "coordinator/cli/dashboard/dashboard_server.h"
#include "coordinator/cli/dashboard/dashboard_token.h"
#include "coordinator/cli/dashboard/farm_poller.h"

namespace portico::cli {

namespace {
struct DashboardOptions {
  ConnectOptions connect;
  std::string listen = "127.0.0.1:8080";
  std::string tokenFile;   // "": defaultDashboardTokenPath()
  bool newToken = false;
  double pollSeconds = 1.0;
  uint32_t previewSide = 640;
};

int runDashboard(const DashboardOptions& o) {
  const DashboardListen listen = parseDashboardListen(o.listen);
  const std::string tokenFile = o.tokenFile.empty() ? defaultDashboardTokenPath() : o.tokenFile;
  const std::string token = loadOrCreateDashboardToken(tokenFile, o.newToken);
  // SIGINT and SIGTERM are taken by a thread of their own (sigwait), which
  // stops the server: a handler could not do that safely.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  ConnectOptions connect = o.connect;
  PollSettings poll;
  poll.interval = std::chrono::milliseconds(int64_t(o.pollSeconds * 1000));
  poll.previewInterval = std::max(poll.interval, std::chrono::milliseconds(2000));
  poll.previewSide = o.previewSide;
  // The poller's requests wait less than a command's: a coordinator that
  // does not answer shows on the page within seconds.
  ConnectOptions pollConnect = connect;
  pollConnect.timeoutSeconds = std::min(connect.timeoutSeconds, 5.0);
  FarmPoller poller(pollConnect, poll);
  DashboardServer server(connect, poller, token);
  const int port = server.bind(listen);
  const std::string host = listen.host.find(':') != std::string::npos ? "[" + listen.host + "]" : listen.host;
  std::cout << fmt::format("portico dashboard of {} at http://{}:{}/?token={}\n(the token is kept in {})\n",
                           connect.endpoint, host, port, token, tokenFile)
            << std::flush;
  std::thread signalWaiter([&] {
    int received = 0;
    sigwait(&signals, &received);
    server.stop();
  });
  server.serve();
  poller.stop();
  // Woken by a signal, or the server stopped of itself: send one to finish it.
  pthread_kill(signalWaiter.native_handle(), SIGTERM);
  signalWaiter.join();
  return 0;
}
}  // namespace

void addDashboardCommand(CLI::App& app, CommandTable& table) {
  auto o = std::make_shared<DashboardOptions>();
  auto* dashboard = app.add_subcommand(
      "dashboard", "serve a live web page of the coordinator's jobs and workers (previews, floor plans, cancel); "
                   "docs/dashboard.md");
  addConnectOptions(*dashboard, o->connect);
  dashboard->add_option("--listen", o->listen, "HOST:PORT to serve the page on: loopback only (port 0: any free one)")
      ->capture_default_str();
  dashboard->add_option("--token-file", o->tokenFile,
                        "where the page's token is kept (default: $XDG_CONFIG_HOME/portico/dashboard/token, else "
                        "~/.config/portico/dashboard/token)");
  dashboard->add_flag("--new-token", o->newToken, "replace the kept token with a new one (old URLs stop working)");
  dashboard->add_option("--poll", o->pollSeconds, "seconds between polls of the coordinator (shared by every viewer)")
      ->capture_default_str()
      ->check(realNumber(0.2, 3600));
  dashboard->add_option("--preview-size", o->previewSide, "pixels on the preview's longer side")
      ->capture_default_str()
      ->check(wholeNumber(16, 1024));
  table.add(dashboard, [o] { return runDashboard(*o); });
}

}  // namespace portico::cli
