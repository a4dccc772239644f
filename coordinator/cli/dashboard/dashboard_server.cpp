#include "coordinator/cli/dashboard/dashboard_server.h"

#include <arpa/inet.h>
#include <fmt/format.h>
#include <httplib.h>
#include <spdlog/spdlog.h>

#include <charconv>
#include <cmath>
#include <map>
#include <mutex>
#include <stdexcept>

#include "common/image/png_file.h"
#include "common/net/client.h"
#include "coordinator/job_limits.h"
#include "coordinator/cli/dashboard/dashboard_page.h"
#include "coordinator/cli/dashboard/dashboard_token.h"
#include "coordinator/cli/dashboard/plan_geometry.h"

namespace portico::cli {

namespace {
constexpr const char* kCookie = "portico_dashboard_token";
constexpr const char* kTokenHeader = "X-Portico-Token";
constexpr auto kKeepAlive = std::chrono::seconds(15);   // an SSE comment: proxies keep the stream open
constexpr int kServerThreads = 16;                      // each open page holds one for its event stream
constexpr double kMaxExposureStops = 20;

bool isLoopback(const std::string& host) {
  if (host == "localhost") return true;
  in_addr v4{};
  if (::inet_pton(AF_INET, host.c_str(), &v4) == 1) return (ntohl(v4.s_addr) >> 24) == 127;
  in6_addr v6{};
  return ::inet_pton(AF_INET6, host.c_str(), &v6) == 1 && IN6_IS_ADDR_LOOPBACK(&v6);
}

std::optional<uint64_t> jobNumber(const std::string& text) {
  uint64_t value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || value == 0) return std::nullopt;
  return value;
}

std::string cookieToken(const httplib::Request& request) {
  const std::string cookies = request.get_header_value("Cookie");
  const std::string name = std::string(kCookie) + "=";
  for (size_t at = 0; at < cookies.size();) {
    const size_t end = std::min(cookies.find(';', at), cookies.size());
    std::string pair = cookies.substr(at, end - at);
    pair.erase(0, pair.find_first_not_of(' '));
    if (pair.rfind(name, 0) == 0) return pair.substr(name.size());
    at = end + 1;
  }
  return "";
}

void refuse(httplib::Response& response, int status, const std::string& why) {
  response.status = status;
  response.set_content(why + "\n", "text/plain; charset=utf-8");
}

void sendJson(httplib::Response& response, const nlohmann::json& body) {
  response.set_header("Cache-Control", "no-store");
  response.set_content(body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), "application/json");
}
}  // namespace

DashboardListen parseDashboardListen(const std::string& text) {
  const size_t colon = text.rfind(':');
  if (colon == std::string::npos)
    throw std::invalid_argument(fmt::format("--listen {}: not HOST:PORT (e.g. 127.0.0.1:8080)", text));
  DashboardListen listen;
  listen.host = text.substr(0, colon);
  if (listen.host.size() > 2 && listen.host.front() == '[' && listen.host.back() == ']')
    listen.host = listen.host.substr(1, listen.host.size() - 2);
  const std::string port = text.substr(colon + 1);
  const auto [end, error] = std::from_chars(port.data(), port.data() + port.size(), listen.port);
  if (error != std::errc() || end != port.data() + port.size() || listen.port < 0 || listen.port > 65535)
    throw std::invalid_argument(fmt::format("--listen {}: '{}' is not a port (0 to 65535; 0: any free one)", text, port));
  if (!isLoopback(listen.host))
    throw std::invalid_argument(fmt::format(
        "--listen {}: the dashboard listens on loopback only (127.x.x.x, localhost, [::1]): its page is plain HTTP "
        "and its token would cross the network; from another machine, tunnel to it: ssh -L 8080:127.0.0.1:8080 HOST",
        text));
  return listen;
}

struct DashboardServer::Impl {
  ConnectOptions connect;
  FarmPoller& poller;
  std::string token;
  httplib::Server server;
  int port = 0;
  std::string host;
  std::mutex planMutex;
  std::map<std::string, nlohmann::json> plans;   // by store directory: read once

  Impl(const ConnectOptions& c, FarmPoller& p, std::string t) : connect(c), poller(p), token(std::move(t)) {}

  // Actions get a connection of their own: the poller's is its thread's.
  net::CoordinatorClient client() const {
    return net::CoordinatorClient(connect.endpoint, connect.keys,
                                  std::chrono::milliseconds(int64_t(connect.timeoutSeconds * 1000)), net::Role::Client);
  }

  // The names this server answers to: a page reached under another name
  // (DNS rebinding) is refused, whatever it carries.
  bool knownHost(const std::string& hostHeader) const {
    for (const std::string& name : {host, std::string("localhost"), std::string("127.0.0.1"), std::string("[::1]")})
      if (hostHeader == name + ":" + std::to_string(port)) return true;
    return host.find(':') != std::string::npos && hostHeader == fmt::format("[{}]:{}", host, port);
  }

  httplib::Server::HandlerResponse authorize(const httplib::Request& request, httplib::Response& response) {
    if (!knownHost(request.get_header_value("Host"))) {
      refuse(response, 403, "this dashboard answers to its own address only");
      return httplib::Server::HandlerResponse::Handled;
    }
    // Opening the printed URL: the token becomes a cookie, and leaves the address bar.
    if (request.method == "GET" && request.path == "/" && request.has_param("token")) {
      if (!sameToken(request.get_param_value("token"), token)) {
        refuse(response, 403, "wrong dashboard token");
        return httplib::Server::HandlerResponse::Handled;
      }
      response.set_header("Set-Cookie", fmt::format("{}={}; Path=/; HttpOnly; SameSite=Strict", kCookie, token));
      response.set_redirect("/", 303);
      return httplib::Server::HandlerResponse::Handled;
    }
    const std::string header = request.get_header_value(kTokenHeader), cookie = cookieToken(request);
    if (header.empty() && cookie.empty()) {
      refuse(response, 401, "this dashboard needs its token: open the URL `portico dashboard` printed");
      return httplib::Server::HandlerResponse::Handled;
    }
    if ((!header.empty() && !sameToken(header, token)) || (!cookie.empty() && !sameToken(cookie, token))) {
      refuse(response, 403, "wrong dashboard token");
      return httplib::Server::HandlerResponse::Handled;
    }
    if (request.method != "GET" && request.method != "HEAD") {
      // A cookie goes with any request to this server; the header only
      // with those its own page makes.
      if (header.empty()) {
        refuse(response, 403, fmt::format("actions need the {} header", kTokenHeader));
        return httplib::Server::HandlerResponse::Handled;
      }
      const std::string origin = request.get_header_value("Origin");
      if (!origin.empty() && origin != "http://" + request.get_header_value("Host")) {
        refuse(response, 403, "an action from another site's page");
        return httplib::Server::HandlerResponse::Handled;
      }
    }
    response.set_header("X-Frame-Options", "DENY");
    response.set_header("X-Content-Type-Options", "nosniff");
    response.set_header("Referrer-Policy", "no-referrer");
    return httplib::Server::HandlerResponse::Unhandled;
  }

  void page(const httplib::Request&, httplib::Response& response) {
    std::string html(kDashboardPage);
    // The page sends the token back in a header with each action.
    const std::string placeholder = "{{TOKEN}}";
    html.replace(html.find(placeholder), placeholder.size(), token);
    response.set_header("Cache-Control", "no-store");
    response.set_header("Content-Security-Policy",
                        "default-src 'self'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; "
                        "img-src 'self'; connect-src 'self'; frame-ancestors 'none'; form-action 'none'");
    response.set_content(html, "text/html; charset=utf-8");
  }

  void events(const httplib::Request& request, httplib::Response& response) {
    std::optional<uint64_t> job;
    if (request.has_param("job")) job = jobNumber(request.get_param_value("job"));
    if (job) poller.watch(*job);
    response.set_header("Cache-Control", "no-store");
    auto seen = std::make_shared<uint64_t>(UINT64_MAX);
    response.set_chunked_content_provider(
        "text/event-stream",
        [this, job, seen](size_t, httplib::DataSink& sink) {
          if (poller.stopping()) return false;
          const uint64_t version = *seen == UINT64_MAX ? *seen - 1 : poller.waitForChange(*seen, kKeepAlive);
          if (poller.stopping() || !sink.is_writable()) return false;
          std::string event;
          if (version == *seen) {
            event = ": still here\n\n";
          } else {
            const nlohmann::json snap = poller.snapshot(job);
            *seen = snap["version"].get<uint64_t>();
            event = "data: " + snap.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n\n";
          }
          return sink.write(event.data(), event.size());
        },
        [this, job](bool) {
          if (job) poller.unwatch(*job);
        });
  }

  void preview(const httplib::Request& request, httplib::Response& response) {
    const auto job = jobNumber(request.matches[1]);
    const auto frame = job ? poller.preview(*job) : std::nullopt;
    if (!frame) return refuse(response, 404, "no preview of this job (yet)");
    // Stops of exposure relative to the job's own --exposure.
    double stops = 0;
    if (request.has_param("stops")) {
      const std::string text = request.get_param_value("stops");
      const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), stops);
      if (error != std::errc() || end != text.data() + text.size() || !std::isfinite(stops) ||
          std::fabs(stops) > kMaxExposureStops)
        return refuse(response, 400, fmt::format("stops: a number from -{0} to {0}", kMaxExposureStops));
    }
    const float exposure = frame->exposure * float(std::exp2(stops));
    std::vector<uint8_t> bytes(frame->image.rgb.size());
    for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = toneMapToByte(frame->image.rgb[i], exposure);
    response.set_header("Cache-Control", "no-store");
    response.set_content(encodePng(frame->image.width, frame->image.height, bytes), "image/png");
  }

  void plan(const httplib::Request& request, httplib::Response& response) {
    const auto job = jobNumber(request.matches[1]);
    const nlohmann::json snap = poller.snapshot(job);
    const auto& status = snap["job"]["status"];
    if (!job || !status.is_object() || !status.contains("settings"))
      return refuse(response, 404, "no such job (yet)");
    const std::string store = status["settings"].value("store", "");
    // Another user's job: the coordinator keeps its store's path from us.
    if (store.empty()) return refuse(response, 404, "no floor plan: another user's job");
    std::lock_guard<std::mutex> lock(planMutex);
    auto it = plans.find(store);
    if (it == plans.end()) {
      nlohmann::json plan;
      try {
        plan = planGeometry(store);
      } catch (const std::exception& e) {
        // The store may live where only the coordinator and workers read it.
        plan = {{"error", fmt::format("no floor plan: the scene store cannot be read here ({})", e.what())}};
      }
      it = plans.emplace(store, std::move(plan)).first;
    }
    sendJson(response, it->second);
  }

  void priority(const httplib::Request& request, httplib::Response& response) {
    const auto job = jobNumber(request.matches[1]);
    if (!job) return refuse(response, 404, "no such job");
    const std::string text = request.get_param_value("priority");
    int32_t value = 0;
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (text.empty() || error != std::errc() || end != text.data() + text.size() || value < limits::kMinPriority ||
        value > limits::kMaxPriority)
      return refuse(response, 400, fmt::format("priority: a whole number from {} to {}", limits::kMinPriority,
                                               limits::kMaxPriority));
    try {
      const auto status = nlohmann::json::parse(client().setPriority(*job, value));
      spdlog::info("job {}: priority {} from the page", *job, value);
      sendJson(response, {{"job", *job}, {"priority", status.value("priority", value)}, {"state", status.value("state", "?")}});
    } catch (const std::exception& e) {
      refuse(response, 502, e.what());
    }
  }

  void cancel(const httplib::Request& request, httplib::Response& response) {
    const auto job = jobNumber(request.matches[1]);
    if (!job) return refuse(response, 404, "no such job");
    try {
      const auto status = nlohmann::json::parse(client().cancel(*job));
      spdlog::info("job {} cancelled from the page: {}", *job, status.value("state", "?"));
      sendJson(response, {{"job", *job}, {"state", status.value("state", "?")}});
    } catch (const std::exception& e) {
      refuse(response, 502, e.what());
    }
  }
};

DashboardServer::DashboardServer(const ConnectOptions& connect, FarmPoller& poller, std::string token)
    : impl_(std::make_unique<Impl>(connect, poller, std::move(token))) {
  auto& s = impl_->server;
  Impl* impl = impl_.get();
  s.new_task_queue = [] { return new httplib::ThreadPool(kServerThreads); };
  s.set_pre_routing_handler([impl](const auto& request, auto& response) { return impl->authorize(request, response); });
  s.Get("/", [impl](const auto& request, auto& response) { impl->page(request, response); });
  s.Get("/api/events", [impl](const auto& request, auto& response) { impl->events(request, response); });
  s.Get("/api/state", [impl](const auto& request, auto& response) {
    std::optional<uint64_t> job;
    if (request.has_param("job")) job = jobNumber(request.get_param_value("job"));
    sendJson(response, impl->poller.snapshot(job));
  });
  s.Get(R"(/api/jobs/(\d+)/preview\.png)", [impl](const auto& request, auto& response) { impl->preview(request, response); });
  s.Get(R"(/api/jobs/(\d+)/plan)", [impl](const auto& request, auto& response) { impl->plan(request, response); });
  s.Post(R"(/api/jobs/(\d+)/cancel)", [impl](const auto& request, auto& response) { impl->cancel(request, response); });
  s.Post(R"(/api/jobs/(\d+)/priority)", [impl](const auto& request, auto& response) { impl->priority(request, response); });
}

DashboardServer::~DashboardServer() = default;

int DashboardServer::bind(const DashboardListen& listen) {
  impl_->host = listen.host;
  const int port = listen.port == 0 ? impl_->server.bind_to_any_port(listen.host.c_str())
                                    : (impl_->server.bind_to_port(listen.host.c_str(), listen.port) ? listen.port : -1);
  if (port <= 0)
    throw std::runtime_error(fmt::format("cannot listen on {}:{} (in use? another dashboard?)", listen.host, listen.port));
  impl_->port = port;
  return port;
}

void DashboardServer::serve() { impl_->server.listen_after_bind(); }

void DashboardServer::stop() { impl_->server.stop(); }

}  // namespace portico::cli
