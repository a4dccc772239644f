#include "coordinator/cli/dashboard/farm_poller.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstring>
#include <set>

#include "common/net/client.h"

namespace portico::cli {

namespace {
using Clock = std::chrono::steady_clock;

bool ended(const std::string& state) { return state == "done" || state == "failed" || state == "cancelled"; }

int64_t number(const nlohmann::json& object, std::initializer_list<const char*> path) {
  const nlohmann::json* at = &object;
  for (const char* key : path) {
    if (!at->is_object() || !at->contains(key)) return 0;
    at = &(*at)[key];
  }
  return at->is_number() ? at->get<int64_t>() : 0;
}
}  // namespace

double FarmPoller::Rate::update(int64_t value, Clock::time_point when) {
  constexpr auto kRateWindow = std::chrono::seconds(5);
  samples.emplace_back(when, value);
  while (samples.size() > 2 && when - samples[1].first >= kRateWindow) samples.pop_front();
  const double seconds = std::chrono::duration<double>(when - samples.front().first).count();
  return seconds > 0.05 ? double(std::max<int64_t>(0, value - samples.front().second)) / seconds : 0.0;
}

FarmPoller::FarmPoller(ConnectOptions connect, PollSettings settings)
    : connect_(std::move(connect)), settings_(settings), thread_([this] { run(); }) {}

FarmPoller::~FarmPoller() { stop(); }

void FarmPoller::stop() {
  stopping_ = true;
  changed_.notify_all();
  if (thread_.joinable() && thread_.get_id() != std::this_thread::get_id()) thread_.join();
}

uint64_t FarmPoller::waitForChange(uint64_t seen, std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait_for(lock, timeout, [&] { return version_ != seen || stopping_; });
  return version_;
}

void FarmPoller::watch(uint64_t job) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++watchers_[job];
}

void FarmPoller::unwatch(uint64_t job) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (auto it = watchers_.find(job); it != watchers_.end() && --it->second <= 0) watchers_.erase(it);
}

std::optional<PreviewFrame> FarmPoller::preview(uint64_t job) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = previews_.find(job);
  if (it == previews_.end()) return std::nullopt;
  return it->second;
}

// What the jobs table shows of a job: its state and phase, progress and
// ETA, photons and rays per second (over the last poll), its error.
nlohmann::json FarmPoller::summary(const nlohmann::json& status, Clock::time_point now) {
  const uint64_t job = status.value("job", uint64_t(0));
  const std::string state = status.value("state", "");
  const auto rate = [&](const char* what, int64_t value) {
    return rates_[fmt::format("job {} {}", job, what)].update(value, now);
  };
  nlohmann::json s = {{"job", job},
                      {"state", state},
                      {"error", status.value("error", "")},
                      {"fraction", status.contains("progress") ? status["progress"].value("fraction", 0.0) : 0.0},
                      {"elapsed_s", status.value("elapsed_s", 0.0)},
                      {"photons_per_s", ended(state) ? 0.0 : rate("photons", number(status, {"progress", "photons_done"}))},
                      {"rays_per_s", ended(state) ? 0.0 : rate("rays", number(status, {"rays", "traced"}))},
                      {"passes_done", number(status, {"render_passes", "done"})}};
  if (status.contains("eta_s")) s["eta_s"] = status["eta_s"];
  if (status.contains("waiting")) s["waiting"] = status["waiting"];
  if (status.contains("priority")) s["priority"] = status["priority"];
  return s;
}

nlohmann::json FarmPoller::snapshot(std::optional<uint64_t> job) {
  std::lock_guard<std::mutex> lock(mutex_);
  nlohmann::json jobs = nlohmann::json::array();
  if (farm_.contains("jobs"))
    for (const auto& listed : farm_["jobs"]) {
      const uint64_t id = listed.value("job", uint64_t(0));
      const auto status = statuses_.find(id);
      jobs.push_back(status != statuses_.end() ? status->second["summary"] : listed);
    }
  nlohmann::json snap = {{"version", version_},
                         {"coordinator", connect_.endpoint},
                         {"error", error_},
                         {"jobs", jobs},
                         {"workers", farm_.value("workers", nlohmann::json::array())}};
  if (job) {
    nlohmann::json view = {{"job", *job}, {"status", nullptr}, {"detail", nullptr}, {"preview", nullptr}};
    if (auto it = statuses_.find(*job); it != statuses_.end()) view["status"] = it->second["status"];
    if (auto it = details_.find(*job); it != details_.end()) view["detail"] = it->second;
    if (auto it = previews_.find(*job); it != previews_.end())
      view["preview"] = {{"version", it->second.cameraRaysDone},
                         {"width", it->second.image.width},
                         {"height", it->second.image.height},
                         {"exposure", it->second.exposure}};
    snap["job"] = view;
  }
  return snap;
}

void FarmPoller::run() {
  std::optional<net::CoordinatorClient> client;
  while (!stopping_) {
    const auto started = Clock::now();
    try {
      // A request that timed out may still be answered: a fresh socket
      // keeps that late answer from being read as the next one's.
      if (!client)
        client.emplace(connect_.endpoint, connect_.keys,
                       std::chrono::milliseconds(int64_t(connect_.timeoutSeconds * 1000)), net::Role::Client);
      pollRound(*client);
    } catch (const std::exception& e) {
      client.reset();
      std::lock_guard<std::mutex> lock(mutex_);
      if (error_ != e.what()) spdlog::warn("{}", e.what());
      error_ = e.what();
      ++version_;
      changed_.notify_all();
    }
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait_until(lock, started + settings_.interval, [&] { return stopping_.load(); });
  }
}

void FarmPoller::pollRound(net::CoordinatorClient& client) {
  nlohmann::json farm = nlohmann::json::parse(client.statusJson(0));
  // The newest jobs first, at most listedJobs of them.
  auto& jobs = farm["jobs"];
  std::sort(jobs.begin(), jobs.end(), [](const auto& a, const auto& b) { return a["job"] > b["job"]; });
  if (jobs.size() > settings_.listedJobs) jobs.erase(jobs.begin() + std::ptrdiff_t(settings_.listedJobs), jobs.end());
  const auto now = Clock::now();
  for (auto& worker : farm["workers"])
    worker["leases_per_s"] = rates_[fmt::format("worker {} leases", worker.value("name", ""))].update(
        worker.value("leases_done", int64_t(0)), now);

  std::map<uint64_t, int> watched;
  std::map<uint64_t, std::string> knownState;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    watched = watchers_;
    for (const auto& [id, status] : statuses_) knownState[id] = status["status"].value("state", "");
  }
  // Active jobs every round (the newest polledJobs); an ended one once more,
  // when its state changed since it was last polled.
  std::map<uint64_t, nlohmann::json> fresh;
  size_t activePolled = 0;
  for (const auto& listed : jobs) {
    const uint64_t id = listed["job"];
    const std::string state = listed.value("state", "");
    const bool active = !ended(state);
    const auto known = knownState.find(id);
    if (active ? activePolled++ >= settings_.polledJobs : known != knownState.end() && known->second == state) continue;
    nlohmann::json status = nlohmann::json::parse(client.statusJson(id));
    if (status.value("job", uint64_t(0)) != id) continue;   // a late answer to another request
    fresh[id] = {{"status", status}, {"summary", summary(status, now)}};
  }

  std::map<uint64_t, nlohmann::json> details;
  std::map<uint64_t, PreviewFrame> previews;
  for (const auto& [id, viewers] : watched) {
    std::string state;
    if (auto it = fresh.find(id); it != fresh.end()) state = it->second["status"].value("state", "");
    else if (auto known = knownState.find(id); known != knownState.end()) state = known->second;
    else continue;   // not listed
    bool due;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      const auto polled = detailPolled_.find(id);
      // Active: at most every previewInterval; ended: once, after it ended.
      due = polled == detailPolled_.end() || (!ended(state) && now - polled->second >= settings_.previewInterval) ||
            (ended(state) && fresh.count(id));
    }
    if (!due) continue;
    nlohmann::json detail = nlohmann::json::parse(client.jobDetailJson(id));
    if (detail.value("job", uint64_t(0)) == id) details[id] = std::move(detail);
    if (state == "render" || state == "done" || state == "cancelled" || state == "failed") {
      try {
        const auto reply = client.fetchPreview(id, settings_.previewSide);
        const auto preview = reply->envelope().getPreview();
        // None with its error (nothing rendered yet; another user's job).
        if (preview.getJob() == id && preview.getWidth() > 0 && preview.getHeight() > 0) {
          PreviewFrame frame;
          frame.image.width = preview.getWidth();
          frame.image.height = preview.getHeight();
          frame.image.rgb.resize(size_t(frame.image.width) * frame.image.height * 3);
          if (preview.getRgb().size() == frame.image.rgb.size() * sizeof(float)) {
            std::memcpy(frame.image.rgb.data(), preview.getRgb().begin(), preview.getRgb().size());
            frame.exposure = preview.getExposure();
            frame.cameraRaysDone = preview.getCameraRaysDone();
            previews[id] = std::move(frame);
          }
        }
      } catch (const std::runtime_error&) {
        // No film yet (nothing rendered; an analysis): the page says so.
      }
    }
  }

  std::lock_guard<std::mutex> lock(mutex_);
  farm_ = std::move(farm);
  for (auto& [id, status] : fresh) statuses_[id] = std::move(status);
  for (auto& [id, detail] : details) {
    details_[id] = std::move(detail);
    detailPolled_[id] = now;
  }
  for (auto& [id, frame] : previews) previews_[id] = std::move(frame);
  // Forget what is no longer listed nor watched.
  std::set<uint64_t> keep;
  for (const auto& listed : farm_["jobs"]) keep.insert(listed["job"].get<uint64_t>());
  for (const auto& [id, viewers] : watchers_) keep.insert(id);
  for (auto* map : {&statuses_, &details_})
    for (auto it = map->begin(); it != map->end();) it = keep.count(it->first) ? std::next(it) : map->erase(it);
  for (auto it = previews_.begin(); it != previews_.end();) it = keep.count(it->first) ? std::next(it) : previews_.erase(it);
  for (auto it = detailPolled_.begin(); it != detailPolled_.end();)
    it = watchers_.count(it->first) ? std::next(it) : detailPolled_.erase(it);
  // Rates of jobs and workers gone, and those not updated this round.
  for (auto it = rates_.begin(); it != rates_.end();)
    it = it->second.samples.empty() || it->second.samples.back().first != now ? rates_.erase(it) : std::next(it);
  error_.clear();
  ++version_;
  changed_.notify_all();
}

}  // namespace portico::cli
