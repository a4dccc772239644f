// `portico render STORE --views FILE.json -o DIR/`: several views of a store
// after one photon pass. One local coordinator and N workers; the first
// view's job runs the photon pass, and once it renders the other views are
// submitted: the coordinator gives them that job's photon tables
// (coordinator/photon_reuse.h), and their render phases overlap. Each image
// is DIR/<name>.<format>, its statistics beside it.
#include <capnp/message.h>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <functional>
#include <filesystem>
#include <iostream>
#include <memory>
#include <thread>

#include "common/net/client.h"
#include "coordinator/cli/commands.h"
#include "coordinator/cli/local_services.h"
#include "coordinator/cli/progress.h"
#include "coordinator/cli/view_list.h"

namespace portico::cli {

namespace {
// Every view's submit message, checked before anything starts.
std::vector<std::unique_ptr<capnp::MallocMessageBuilder>> viewSubmits(const JobSettings& base,
                                                                      const std::vector<View>& views,
                                                                      const ViewsOptions& options) {
  namespace fs = std::filesystem;
  const std::string& directory = base.output;
  std::error_code error;
  if (fs::exists(directory, error) && !fs::is_directory(directory, error))
    throw std::invalid_argument(fmt::format("-o {}: with --views it names a directory, and this is a file", directory));
  fs::create_directories(directory, error);
  if (error) throw std::invalid_argument(fmt::format("-o {}: cannot create the directory: {}", directory, error.message()));
  std::vector<std::unique_ptr<capnp::MallocMessageBuilder>> submits;
  for (const View& view : views) {
    submits.push_back(std::make_unique<capnp::MallocMessageBuilder>());
    try {
      fillSubmit(viewSettings(base, view, directory, options.format), *submits.back());
    } catch (const std::exception& e) {
      throw std::invalid_argument(fmt::format("{}: view \"{}\": {}", options.file, view.name, e.what()));
    }
  }
  return submits;
}

struct ViewJob {
  const View* view;
  uint64_t job = 0;
  std::string state;
};

// Polls the jobs until each has ended (or the services fail, or Ctrl-C);
// `until`: stop as soon as it holds for the statuses read.
void follow(net::CoordinatorClient& client, LocalServices& services, std::vector<ViewJob>& jobs,
            const std::function<bool()>& until) {
  const auto waitStarted = std::chrono::steady_clock::now();
  while (!interrupted() && !until()) {
    for (ViewJob& j : jobs) {
      if (jobEnded(j.state)) continue;
      nlohmann::json status;
      try {
        status = nlohmann::json::parse(client.statusJson(j.job));
      } catch (const zmq::error_t& e) {
        if (e.num() == EINTR) return;
        throw;
      }
      j.state = status.value("state", "");
      if (!jobEnded(j.state)) continue;
      const auto& reused = status["photon_pass"]["reused_from_job"];
      std::cout << fmt::format("view {}: job {} {} in {:.2f} s{}{}", j.view->name, j.job, j.state,
                               status.value("elapsed_s", 0.0),
                               j.state == "done" ? ", " + status["settings"].value("output", "") : "",
                               reused.is_number() ? fmt::format(" (photon pass of job {})", reused.get<uint64_t>())
                                                  : " (its own photon pass)")
                << (status.value("error", "").empty() ? "" : ": " + status.value("error", "")) << std::endl;
    }
    if (const auto failure = services.failure()) {
      for (ViewJob& j : jobs)
        if (!jobEnded(j.state)) j.state = "failed";
      std::cerr << *failure << "\n";
      return;
    }
    std::this_thread::sleep_for(statusPollInterval(std::chrono::steady_clock::now() - waitStarted));
  }
}
}  // namespace

int runViews(const JobSettings& base, const LocalRunOptions& local, const ViewsOptions& options) {
  if (base.camera || !base.cameraName.empty())
    throw std::invalid_argument("--views gives each view its camera: --camera, --look-from, --look-at, --up and --fov "
                                "go in the views file");
  const std::vector<View> views = readViewList(options.file);
  checkViewsAgainstStore(views, SceneStore::open(base.store), options.file);
  auto submits = viewSubmits(base, views, options);

  LocalServices services(local);
  catchInterrupts();
  net::CoordinatorClient client(services.endpoint(), services.keys());
  std::vector<ViewJob> jobs;
  jobs.push_back({&views[0], client.submit(*submits[0]), "photons"});
  std::cout << fmt::format("view {}: job {} (the photon pass)", views[0].name, jobs[0].job) << std::endl;
  // The others once the first's photon pass is complete: they reuse it.
  follow(client, services, jobs, [&] { return jobs[0].state != "photons"; });
  if (!interrupted() && (jobs[0].state == "render" || jobs[0].state == "done")) {
    for (size_t i = 1; i < views.size(); ++i) {
      jobs.push_back({&views[i], client.submit(*submits[i]), "render"});
      std::cout << fmt::format("view {}: job {}", views[i].name, jobs.back().job) << std::endl;
    }
  } else if (views.size() > 1) {
    std::cerr << fmt::format("the other {} views were not rendered: the first view's job is {}\n", views.size() - 1,
                             jobs[0].state);
  }
  follow(client, services, jobs, [&] {
    for (const ViewJob& j : jobs)
      if (!jobEnded(j.state)) return false;
    return true;
  });
  if (interrupted()) {
    net::CoordinatorClient quick(services.endpoint(), services.keys(), std::chrono::seconds(1));
    for (ViewJob& j : jobs) {
      try {
        if (!jobEnded(j.state)) quick.cancel(j.job);
      } catch (const std::exception&) {
      }
    }
    std::cerr << "interrupted\n";
  }
  bool ok = !interrupted() && jobs.size() == views.size();
  for (const ViewJob& j : jobs) ok = ok && j.state == "done";
  services.stop(!ok || local.keepLogs);
  return ok ? 0 : 1;
}

}  // namespace portico::cli
