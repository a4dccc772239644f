// `portico render`: everything on this machine. Starts a coordinator and N
// workers (LocalServices), submits the job, shows progress, and stops the
// services when the job ends or on Ctrl-C. With --views, several views of
// the store after one photon pass (views_command.cpp).
#include <capnp/message.h>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <iostream>
#include <thread>

#include "common/net/client.h"
#include "coordinator/cli/commands.h"
#include "coordinator/cli/local_services.h"
#include "coordinator/cli/progress.h"

namespace portico::cli {

namespace {
// The sun the coordinator computed for --sun-time, as --sun would give it:
// one line on stderr once the status shows it; false until then.
bool showResolvedSun(const nlohmann::json& status) {
  const auto settings = status.find("settings");
  if (settings == status.end() || !settings->contains("daylight") || !(*settings)["daylight"].is_object()) return false;
  const auto& daylight = (*settings)["daylight"];
  if (!daylight.value("sun", false)) return false;
  std::cerr << fmt::format("sun: --sun {:.2f},{:.2f} (azimuth from +Z towards +X, elevation)\n",
                           daylight.value("sun_azimuth", 0.0), daylight.value("sun_elevation", 0.0));
  return true;
}
}  // namespace

int runRender(const JobSettings& render, const LocalRunOptions& local, const std::vector<Sensor>* sensors) {
  if (local.workers == 0) throw std::invalid_argument("--workers must be at least 1");
  capnp::MallocMessageBuilder submit;
  fillSubmit(render, submit, sensors);   // validates options before anything starts
  LocalServices services(local);
  catchInterrupts();
  net::CoordinatorClient client(services.endpoint(), services.keys());
  const uint64_t job = client.submit(submit);
  ProgressDisplay display(false);
  bool sunShown = false;
  std::string state;
  nlohmann::json status;
  PollPacer pacer(std::chrono::steady_clock::now());
  while (!interrupted()) {
    try {
      status = nlohmann::json::parse(client.statusJson(job));
    } catch (const zmq::error_t& e) {
      if (e.num() == EINTR) continue;   // Ctrl-C: the loop condition decides
      throw;
    }
    if (render.daylight.sunTime && !sunShown) sunShown = showResolvedSun(status);
    display.update(status);
    state = status.value("state", "");
    if (jobEnded(state)) break;
    if (const auto failure = services.failure()) {
      state = "failed";
      status["error"] = *failure;
      break;
    }
    std::this_thread::sleep_for(pacer.next(status, std::chrono::steady_clock::now()));
  }
  if (interrupted()) {
    // A terminal's Ctrl-C reached the services too, and the coordinator may
    // be gone already: a short try, then stop them whatever it answered.
    try {
      net::CoordinatorClient(services.endpoint(), services.keys(), std::chrono::seconds(1)).cancel(job);
    } catch (const std::exception&) {
    }
    state = "cancelled";
    status["error"] = "interrupted";
  }
  display.finish(status);
  const bool ok = state == "done";
  services.stop(!ok || local.keepLogs);
  return ok ? 0 : 1;
}

}  // namespace portico::cli
