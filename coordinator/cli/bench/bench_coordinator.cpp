#include "coordinator/cli/bench/bench_coordinator.h"

#include <capnp/message.h>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <vector>

#include "common/job/job_settings.h"
#include "common/net/client.h"
#include "common/scene/generator/building_generator.h"
#include "common/scene/generator/building_presets.h"
#include "common/scene/store/scene_store.h"
#include "common/util/child_process.h"
#include "common/util/temporary_directory.h"
#include "coordinator/cli/bench/bench_plot.h"
#include "coordinator/cli/bench/simulated_workers.h"
#include "coordinator/cli/commands.h"
#include "coordinator/cli/local_services.h"

namespace portico::cli {

namespace {
int64_t steadyNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// A process's CPU (utime + stime, /proc/PID/stat) and its time waiting for
// a core (run_delay, /proc/PID/schedstat) sampled every 20 ms on a thread of
// the bench, so that any window of the run can be read afterwards. On a
// shared machine the second says how much of the coordinator's wall time
// went to others' work rather than to its own.
class CpuSampler {
 public:
  explicit CpuSampler(pid_t pid) : pid_(pid), thread_([this] { loop(); }) {}
  ~CpuSampler() { stop(); }
  void stop() {
    stopping_ = true;
    if (thread_.joinable()) thread_.join();
  }
  // CPU seconds, and seconds spent waiting for a core, at steady time
  // `ns`, interpolated between samples.
  double secondsAt(int64_t ns) const { return at(ns, &Sample::cpu); }
  double waitAt(int64_t ns) const { return at(ns, &Sample::wait); }
  double lastSeconds() const {
    std::lock_guard lock(mutex_);
    return samples_.empty() ? 0 : samples_.back().cpu;
  }

 private:
  void loop() {
    const double tick = double(::sysconf(_SC_CLK_TCK));
    while (!stopping_) {
      std::ifstream in(fmt::format("/proc/{}/stat", pid_));
      std::string stat((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      const size_t paren = stat.rfind(')');
      if (paren != std::string::npos) {
        std::istringstream fields(stat.substr(paren + 2));
        std::vector<std::string> f;
        for (std::string s; fields >> s && f.size() < 13;) f.push_back(s);
        if (f.size() >= 13) {
          Sample sample{steadyNs(), double(std::stoll(f[11]) + std::stoll(f[12])) / tick, 0};   // fields 14, 15
          std::ifstream schedstat(fmt::format("/proc/{}/schedstat", pid_));
          int64_t running = 0, waiting = 0;
          if (schedstat >> running >> waiting) sample.wait = double(waiting) * 1e-9;
          std::lock_guard lock(mutex_);
          samples_.push_back(sample);
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }

  struct Sample {
    int64_t ns = 0;
    double cpu = 0, wait = 0;
  };
  double at(int64_t ns, double Sample::*field) const {
    std::lock_guard lock(mutex_);
    if (samples_.empty()) return 0;
    auto after = std::lower_bound(samples_.begin(), samples_.end(), ns,
                                  [](const Sample& s, int64_t t) { return s.ns < t; });
    if (after == samples_.begin()) return (*after).*field;
    if (after == samples_.end()) return samples_.back().*field;
    const auto before = after - 1;
    const double f = double(ns - before->ns) / double(std::max<int64_t>(1, after->ns - before->ns));
    return (*before).*field + f * ((*after).*field - (*before).*field);
  }

  pid_t pid_;
  std::atomic<bool> stopping_{false};
  mutable std::mutex mutex_;
  std::vector<Sample> samples_;
  std::thread thread_;
};

// /proc/PID/io: what the coordinator read and wrote (syscalls and disk).
struct ProcessIo {
  int64_t readChars = 0, writtenChars = 0, diskWrites = 0;
};
ProcessIo readProcessIo(pid_t pid) {
  std::ifstream in(fmt::format("/proc/{}/io", pid));
  ProcessIo io;
  std::string key;
  int64_t value = 0;
  while (in >> key >> value) {
    if (key == "rchar:") io.readChars = value;
    else if (key == "wchar:") io.writtenChars = value;
    else if (key == "write_bytes:") io.diskWrites = value;
  }
  return io;
}

struct RunFigures {
  uint32_t workers = 0, processes = 0;
  int64_t leases = 0, windowLeases = 0;
  double windowSeconds = 0, leasesPerSecond = 0, cpuMsPerLease = 0, coordinatorBusy = 0;
  double coordinatorWaiting = 0;      // of the window, the coordinator waited for a core
  double simulatedCpuSeconds = 0;     // the simulated workers' processes, all of the run
  double latencyMedianMs = 0, latencyP99Ms = 0;
  double bytesInPerLease = 0, bytesOutPerLease = 0, diskWritesPerLease = 0;
  // The leases' work (photons emitted, rays handed on and received again,
  // camera rays) and the bytes through the coordinator per unit of it: what
  // the cluster model charges on the coordinator's link (bench cluster --bytes-per-ray).
  int64_t work = 0;
  double bytesPerWork = 0;
  double bytesPerPhaseWork[2] = {0, 0};   // photon pass (photons and rays), render (camera and handed-on rays)
  double jobSeconds = 0, coordinatorCpuSeconds = 0;
  int64_t photons = 0, emitted = 0, depositRecords = 0, regionRecords = 0, photonsHandedOn = 0, cameraRays = 0;
  int64_t refused = 0, errors = 0;
  std::vector<std::string> problems;   // where the job's accounting did not balance
  bool balanced() const { return problems.empty(); }
};

double percentile(std::vector<int64_t>& values, double q) {
  if (values.empty()) return 0;
  const size_t k = std::min(values.size() - 1, size_t(q * double(values.size())));
  std::nth_element(values.begin(), values.begin() + long(k), values.end());
  return double(values[k]);
}

int64_t statusInt(const nlohmann::json& j, const char* section, const char* key) {
  const auto s = j.find(section);
  if (s == j.end() || !s->is_object()) return -1;
  const auto v = s->find(key);
  return v == s->end() || !v->is_number() ? -1 : v->get<int64_t>();
}

// Every photon and ray the simulated workers reported, against what the
// coordinator's statistics say it applied.
void checkAccounting(const nlohmann::json& status, const SimulatedReport& sims, const BenchCoordinatorOptions& o,
                     RunFigures& r) {
  auto expect = [&](const std::string& what, int64_t got, int64_t want) {
    if (got != want) r.problems.push_back(fmt::format("{}: {}, expected {}", what, got, want));
  };
  if (status.value("state", "") != "done")
    r.problems.push_back(fmt::format("job {}: {}", status.value("state", "?"), status.value("error", "")));
  const int64_t emitted = statusInt(status, "photons", "emitted");
  expect("photons emitted", emitted, r.photons);
  expect("photons emitted by the simulated workers", sims.tally.emitted, r.photons);
  // Every photon ended once: a handed-on one in the cell it was handed to.
  expect("photons absorbed + escaped",
         statusInt(status, "photons", "absorbed") + statusInt(status, "photons", "escaped"), emitted);
  expect("photons handed on", statusInt(status, "photons", "crossings"), sims.tally.photonsHandedOn);
  expect("photon deposits", statusInt(status, "photons", "deposits"), sims.tally.depositRecords);
  expect("photon bytes stored",
         statusInt(status, "disk", "photon_bytes_from_workers") + statusInt(status, "disk", "photon_bytes_from_results"),
         sims.tally.depositRecords * int64_t(sizeof(PhotonRecord)));
  expect("photons still queued", statusInt(status, "photons", "queued"), 0);
  expect("camera rays", statusInt(status, "rays", "camera"), int64_t(o.width) * o.height);
  expect("camera rays of the simulated workers", sims.tally.cameraRays, int64_t(o.width) * o.height);
  expect("rays still queued", statusInt(status, "rays", "queued"), 0);
  expect("leases applied", status.value("leases", int64_t(-1)), sims.tally.results);
  r.refused = 0;
  if (status.contains("workers"))
    for (const auto& w : status["workers"]) r.refused += w.value("refused_results", int64_t(0));
  expect("Results refused", r.refused, 0);
  expect("errors the coordinator sent", sims.errors, 0);
}

// Ctrl-C or SIGTERM ends a run by an exception, whose unwinding stops the
// coordinator and the simulated workers (ChildProcess), instead of leaving
// them running without the bench.
void throwIfInterrupted() {
  if (interrupted()) throw std::runtime_error("interrupted: the coordinator and simulated workers were stopped");
}

// Waits for `done`, polling every 20 ms; throws `what` after `seconds`.
template <typename Done>
void waitFor(Done done, double seconds, const std::string& what) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (!done()) {
    throwIfInterrupted();
    if (std::chrono::steady_clock::now() > deadline) throw std::runtime_error(what);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

RunFigures runOnce(uint32_t workers, const std::string& store, const BenchCoordinatorOptions& o,
                   const std::filesystem::path& work) {
  std::filesystem::create_directories(work);
  RunFigures r;
  r.workers = workers;
  const std::string endpoint = "ipc://" + (work / "coordinator.ipc").string();
  const std::string endpointFile = (work / "endpoint").string();
  const std::string coordinatorLog = (work / "coordinator.log").string();
  // As `portico render` starts it (local_services.cpp): ipc:// in a private
  // folder, which admits only this user and root.
  ChildProcess coordinator({findProgram("portico-coordinator"), "--listen", endpoint, "--db",
                            (work / "jobs.db").string(), "--endpoint-file", endpointFile, "--log-level", "warn",
                            "--lease-rays", std::to_string(o.leaseRays)},
                           coordinatorLog);
  waitFor([&] { return std::filesystem::exists(endpointFile) && std::filesystem::file_size(endpointFile) > 0; }, 20,
          fmt::format("the coordinator did not listen within 20 s; see {}", coordinatorLog));

  std::vector<ChildProcess> processes;
  std::vector<std::string> reports;
  const std::string portico = findProgram("portico");
  for (uint32_t first = 0; first < workers; first += o.workersPerProcess) {
    const uint32_t count = std::min(o.workersPerProcess, workers - first);
    reports.push_back((work / fmt::format("simulated-{}.txt", processes.size())).string());
    std::vector<std::string> argv{portico, "bench", "simulated-workers", "--connect", endpoint, "--count",
                                  std::to_string(count), "--first", std::to_string(first), "--report", reports.back(),
                                  "--deposits-per-photon", fmt::format("{}", o.shape.depositsPerPhoton),
                                  "--photon-crossings", fmt::format("{}", o.shape.photonCrossings),
                                  "--camera-crossings", fmt::format("{}", o.shape.cameraCrossings),
                                  "--max-depth", std::to_string(o.shape.maxDepth),
                                  "--rays-per-second", fmt::format("{}", o.shape.raysPerSecond)};
    if (!o.depositRegions) argv.push_back("--no-deposit-regions");
    if (o.shape.miscount) argv.push_back("--miscount");
    processes.emplace_back(argv, (work / fmt::format("simulated-{}.log", processes.size())).string());
  }
  r.processes = uint32_t(processes.size());

  net::CoordinatorClient client(endpoint, "", std::chrono::seconds(60));
  waitFor(
      [&] {
        const auto all = nlohmann::json::parse(client.statusJson(0));
        return all.contains("workers") && all["workers"].size() >= workers;
      },
      60 + workers * 0.1, fmt::format("{} simulated workers did not all join within the time; see {}", workers,
                                      work.string()));

  JobSettings settings;
  settings.store = store;
  settings.output = (work / "image.png").string();
  const SceneStore scene = SceneStore::open(store);
  settings.photons = o.photonsPerLight * scene.lights().size();
  settings.spp = 1;
  settings.gather = 0;
  settings.width = o.width;
  settings.height = o.height;
  r.photons = int64_t(settings.photons);
  capnp::MallocMessageBuilder submit;
  fillSubmit(settings, submit);
  CpuSampler cpu(coordinator.pid());
  const int64_t submitted = steadyNs();
  const uint64_t job = client.submit(submit);
  nlohmann::json status;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(o.timeoutSeconds);
  while (true) {
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    throwIfInterrupted();
    status = nlohmann::json::parse(client.statusJson(job));
    const std::string state = status.value("state", "");
    if (state == "done" || state == "failed" || state == "cancelled") break;
    if (!coordinator.running())
      throw std::runtime_error(fmt::format("the coordinator exited; see {}", coordinatorLog));
    if (std::chrono::steady_clock::now() > deadline)
      throw std::runtime_error(fmt::format("{} workers: the job did not finish within {} s ({}); see {}", workers,
                                           o.timeoutSeconds, status.value("state", "?"), work.string()));
  }
  const int64_t ended = steadyNs();
  const ProcessIo io = readProcessIo(coordinator.pid());
  for (ChildProcess& p : processes) p.kill(SIGTERM);
  for (ChildProcess& p : processes) p.stop(std::chrono::seconds(20));
  cpu.stop();
  r.coordinatorCpuSeconds = cpu.lastSeconds();
  coordinator.stop(std::chrono::seconds(10));

  SimulatedReport sims;
  for (const std::string& path : reports) sims.add(readSimulatedReport(path));
  r.leases = sims.tally.results;
  r.emitted = sims.tally.emitted;
  r.depositRecords = sims.tally.depositRecords;
  r.regionRecords = sims.tally.regionRecords;
  r.photonsHandedOn = sims.tally.photonsHandedOn;
  r.cameraRays = sims.tally.cameraRays;
  r.errors = sims.errors;
  r.simulatedCpuSeconds = sims.cpuSeconds;
  r.jobSeconds = double(ended - submitted) * 1e-9;
  checkAccounting(status, sims, o, r);

  // The steady window: from the Result a tenth of the way through the job
  // to the one nine tenths through (start-up and the tail left out).
  auto& results = sims.results;
  std::sort(results.begin(), results.end());
  if (results.size() >= 10) {
    const size_t begin = results.size() / 10, end = results.size() * 9 / 10;
    const int64_t t0 = results[begin].first, t1 = results[end].first;
    r.windowLeases = int64_t(end - begin);
    r.windowSeconds = double(t1 - t0) * 1e-9;
    if (r.windowSeconds > 0) {
      r.leasesPerSecond = double(r.windowLeases) / r.windowSeconds;
      const double cpuSeconds = cpu.secondsAt(t1) - cpu.secondsAt(t0);
      r.cpuMsPerLease = cpuSeconds * 1e3 / double(r.windowLeases);
      r.coordinatorBusy = cpuSeconds / r.windowSeconds;
      r.coordinatorWaiting = (cpu.waitAt(t1) - cpu.waitAt(t0)) / r.windowSeconds;
    }
    std::vector<int64_t> latencies;
    for (size_t i = begin; i < end; ++i)
      if (results[i].second >= 0) latencies.push_back(results[i].second);
    r.latencyMedianMs = percentile(latencies, 0.5) * 1e-6;
    r.latencyP99Ms = percentile(latencies, 0.99) * 1e-6;
  }
  if (r.leases > 0) {
    r.bytesInPerLease = double(sims.bytesSent) / double(r.leases);
    r.bytesOutPerLease = double(sims.bytesReceived) / double(r.leases);
    r.diskWritesPerLease = double(io.diskWrites) / double(r.leases);
  }
  r.work = sims.tally.emitted + sims.tally.photonsHandedOn + sims.tally.cameraRays + sims.tally.raysHandedOn;
  if (r.work > 0) r.bytesPerWork = double(sims.bytesSent + sims.bytesReceived) / double(r.work);
  const int64_t phaseWork[2] = {sims.tally.emitted + sims.tally.photonsHandedOn,
                                sims.tally.cameraRays + sims.tally.raysHandedOn};
  for (int phase : {0, 1})
    if (phaseWork[phase] > 0) r.bytesPerPhaseWork[phase] = double(sims.phaseBytes[phase]) / double(phaseWork[phase]);
  return r;
}

std::vector<uint32_t> parseCounts(const std::string& text) {
  std::vector<uint32_t> counts;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    size_t used = 0;
    unsigned long value = 0;
    try {
      value = std::stoul(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != item.size() || value == 0 || value > 100000)
      throw std::invalid_argument(fmt::format("--workers: '{}' is not a worker count (1 to 100000)", item));
    counts.push_back(uint32_t(value));
  }
  if (counts.empty()) throw std::invalid_argument("--workers: name at least one worker count");
  return counts;
}

std::string csvOf(const std::vector<RunFigures>& runs) {
  std::string csv =
      "workers,processes,leases,window_leases,window_s,leases_per_s,coordinator_cpu_ms_per_lease,coordinator_busy,"
      "coordinator_waiting,simulated_workers_cpu_s,latency_median_ms,latency_p99_ms,bytes_in_per_lease,bytes_out_per_lease,disk_write_bytes_per_lease,work,bytes_per_work,bytes_per_photon_work,bytes_per_render_work,job_s,"
      "coordinator_cpu_s,photons,emitted,deposit_records,region_records,photons_handed_on,camera_rays,results_refused,"
      "errors,balanced\n";
  for (const RunFigures& r : runs)
    csv += fmt::format(
        "{},{},{},{},{:.6f},{:.1f},{:.4f},{:.3f},{:.3f},{:.3f},{:.3f},{:.3f},{:.0f},{:.0f},{:.0f},{},{:.2f},{:.2f},{:.2f},"
        "{:.3f},{:.3f},{},{},{},{},{},{},{},{},{}\n",
        r.workers, r.processes, r.leases, r.windowLeases, r.windowSeconds, r.leasesPerSecond, r.cpuMsPerLease,
        r.coordinatorBusy, r.coordinatorWaiting, r.simulatedCpuSeconds, r.latencyMedianMs, r.latencyP99Ms,
        r.bytesInPerLease, r.bytesOutPerLease, r.diskWritesPerLease, r.work, r.bytesPerWork, r.bytesPerPhaseWork[0],
        r.bytesPerPhaseWork[1], r.jobSeconds, r.coordinatorCpuSeconds, r.photons, r.emitted, r.depositRecords,
        r.regionRecords, r.photonsHandedOn, r.cameraRays, r.refused, r.errors, r.balanced() ? 1 : 0);
  return csv;
}

void printTable(const std::vector<RunFigures>& runs) {
  std::cout << "\n| workers | leases | leases/s | coordinator CPU per lease | coordinator busy, waiting for a core | "
               "Result→Assign median | p99 | bytes in / out per lease | job | simulated workers' CPU | balanced |\n"
               "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const RunFigures& r : runs)
    std::cout << fmt::format("| {} | {} | {:.0f} | {:.3f} ms | {:.0f} %, {:.0f} % | {:.2f} ms | {:.2f} ms | "
                             "{:.0f} / {:.0f} | {:.1f} s | {:.1f} s | {} |\n",
                             r.workers, r.leases, r.leasesPerSecond, r.cpuMsPerLease, 100 * r.coordinatorBusy,
                             100 * r.coordinatorWaiting, r.latencyMedianMs, r.latencyP99Ms, r.bytesInPerLease,
                             r.bytesOutPerLease, r.jobSeconds, r.simulatedCpuSeconds, r.balanced() ? "yes" : "NO");
  std::cout.flush();
}

void writePlot(const std::string& path, const std::string& title, const std::vector<RunFigures>& runs) {
  const auto panel = [](const std::string& name, const char* y, bool logY) {
    PlotPanel p;
    p.title = name, p.xLabel = "simulated workers", p.yLabel = y, p.logX = true, p.logY = logY;
    return p;
  };
  PlotPanel rate = panel(title, "leases per second", false);
  PlotPanel latency = panel("Result to next Assign", "milliseconds", true);
  PlotPanel cpu = panel("coordinator CPU per lease", "milliseconds", true);
  const auto series = [](const char* label, std::array<uint8_t, 3> color, bool dashed = false) {
    PlotSeries s;
    s.label = label, s.color = color, s.dashed = dashed;
    return s;
  };
  PlotSeries leases = series("leases/s", {31, 119, 180}), target = series("target", {150, 150, 150}, true);
  PlotSeries median = series("median", {31, 119, 180}), p99 = series("p99", {214, 39, 40});
  PlotSeries p99Target = series("target", {150, 150, 150}, true);
  PlotSeries perLease = series("per lease", {44, 160, 44});
  for (const RunFigures& r : runs) {
    leases.x.push_back(r.workers), leases.y.push_back(r.leasesPerSecond);
    median.x.push_back(r.workers), median.y.push_back(r.latencyMedianMs);
    p99.x.push_back(r.workers), p99.y.push_back(r.latencyP99Ms);
    perLease.x.push_back(r.workers), perLease.y.push_back(r.cpuMsPerLease);
  }
  target.x = {double(runs.front().workers), double(runs.back().workers)}, target.y = {2500, 2500};
  p99Target.x = target.x, p99Target.y = {20, 20};
  rate.series = {leases, target};
  latency.series = {median, p99, p99Target};
  cpu.series = {perLease};
  writePlotPng(path, {rate, latency, cpu}, 480, 400);
}
}  // namespace

int runBenchCoordinator(BenchCoordinatorOptions o, bool workersGiven, bool floorsGiven, bool photonsGiven) {
  if (o.quick) {
    if (!workersGiven) o.workers = "4,16";
    if (!floorsGiven) o.floors = 2;
    if (!photonsGiven) o.photonsPerLight = 200;
  }
  const std::vector<uint32_t> counts = parseCounts(o.workers);
  catchInterrupts();
  if (o.workersPerProcess == 0) throw std::invalid_argument("--workers-per-process must be at least 1");
  const std::optional<BuildingPreset> preset = findBuildingPreset(o.preset, o.floors);
  if (!preset)
    throw std::invalid_argument(fmt::format("unknown preset '{}' (known: {})", o.preset,
                                            fmt::join(buildingPresetNames(), ", ")));
  // A thousand workers are a thousand connections to the coordinator, each a
  // descriptor; the coordinator inherits this limit.
  rlimit files{};
  if (::getrlimit(RLIMIT_NOFILE, &files) == 0 && files.rlim_cur < files.rlim_max) {
    files.rlim_cur = files.rlim_max;
    ::setrlimit(RLIMIT_NOFILE, &files);
  }
  TemporaryDirectory temporary("portico-bench-coordinator");
  if (o.keep) temporary.keep();
  const std::filesystem::path& work = temporary.path();
  std::string store = o.store.empty() ? (work / "store").string() : std::filesystem::absolute(o.store).string();
  if (std::filesystem::exists(std::filesystem::path(store) / "scene.db")) {
    std::cout << fmt::format("portico bench coordinator: reusing the scene store {}\n", store);
  } else {
    std::cout << fmt::format("portico bench coordinator: generating {} ({} floors) into {} ...\n", o.preset,
                             preset->floors, store);
    std::cout.flush();
    const GeneratedBuildingStats g = generateBuilding(*preset, o.sceneSeed, store);
    std::cout << fmt::format("  {} cells, {} portals, {} lights in {:.1f} s\n", g.cells, g.portals, g.lights,
                             g.seconds);
  }
  const SceneStore scene = SceneStore::open(store);
  std::cout << fmt::format(
      "job: {} photons ({} per light of {}), {}x{} at 1 spp; coordinator --lease-rays {}; simulated workers answer "
      "at once: {} deposit records and {} crossings per photon, {} crossings per camera ray, deposits {}; "
      "{} workers per process\n",
      o.photonsPerLight * scene.lights().size(), o.photonsPerLight, scene.lights().size(), o.width, o.height,
      o.leaseRays, o.shape.depositsPerPhoton, o.shape.photonCrossings, o.shape.cameraCrossings,
      o.depositRegions ? "into their regions" : "in the Results", o.workersPerProcess);
  std::cout.flush();

  std::vector<RunFigures> runs;
  for (const uint32_t n : counts) {
    std::cout << fmt::format("{} simulated workers ...\n", n);
    std::cout.flush();
    runs.push_back(runOnce(n, store, o, work / fmt::format("run-{}", n)));
    const RunFigures& r = runs.back();
    std::cout << fmt::format("  {} leases in {:.1f} s; steady window {:.1f} s: {:.0f} leases/s, {:.3f} ms of "
                             "coordinator CPU per lease, latency median {:.2f} ms, p99 {:.2f} ms\n",
                             r.leases, r.jobSeconds, r.windowSeconds, r.leasesPerSecond, r.cpuMsPerLease,
                             r.latencyMedianMs, r.latencyP99Ms);
    for (const std::string& problem : r.problems) std::cout << "  NOT BALANCED: " << problem << "\n";
    std::cout.flush();
  }
  printTable(runs);
  if (!o.csv.empty()) {
    std::ofstream out(o.csv);
    out << csvOf(runs);
    if (!out) throw std::runtime_error("cannot write " + o.csv + " (check the directory exists)");
    std::cout << "wrote " << o.csv << "\n";
  }
  if (!o.plot.empty()) {
    writePlot(o.plot,
              fmt::format("{}, {} photons", std::filesystem::path(store).filename().string(),
                          o.photonsPerLight * scene.lights().size()),
              runs);
    std::cout << "wrote " << o.plot << "\n";
  }
  if (o.keep) std::cout << "runs kept in " << work.string() << "\n";
  const bool balanced = std::all_of(runs.begin(), runs.end(), [](const RunFigures& r) { return r.balanced(); });
  return balanced ? 0 : 1;
}

}  // namespace portico::cli
