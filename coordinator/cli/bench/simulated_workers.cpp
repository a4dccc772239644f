#include "coordinator/cli/bench/simulated_workers.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>

#include <chrono>
#include <deque>
#include <fstream>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <utility>
#include <zmq.hpp>

#include "common/net/message.h"

namespace portico::cli {

namespace {
volatile sig_atomic_t stopRequested = 0;
void onStop(int) { stopRequested = 1; }

double processCpuSeconds() {
  rusage usage{};
  ::getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) + 1e-6 * double(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

int64_t steadyNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

struct SimulatedWorker {
  std::string name;
  std::optional<zmq::socket_t> socket;
  bool welcomed = false;
  int64_t heartbeatNs = 1'000'000'000;
  int64_t lastSentNs = 0;
  uint64_t progress = 0;
  std::deque<size_t> resultsAwaitingAssign;   // samples of the Results not yet followed by an Assign
  std::set<std::pair<uint64_t, uint32_t>> photonsHeld;   // (photon job, cell) fetched once, as a worker caches them
  std::deque<std::unique_ptr<net::Decoded>> waiting;    // render leases waiting for their cell's photons
  std::optional<std::pair<uint64_t, uint32_t>> fetching;
};

class WorkerProcess {
 public:
  explicit WorkerProcess(const SimulatedWorkersOptions& options) : options_(options), context_(1) {
    workers_.resize(options.count);
    for (uint32_t i = 0; i < options.count; ++i) {
      SimulatedWorker& w = workers_[i];
      w.name = fmt::format("sim-{}", options.first + i);
      w.socket.emplace(context_, zmq::socket_type::dealer);
      w.socket->set(zmq::sockopt::linger, 0);
      w.socket->set(zmq::sockopt::routing_id, w.name);
      w.socket->set(zmq::sockopt::maxmsgsize, int64_t(net::kMaxFrameBytes));
      w.socket->connect(options.endpoint);
      capnp::MallocMessageBuilder message;
      auto hello = message.initRoot<wire::Envelope>().initHello();
      hello.setVersion(wire::PROTOCOL_VERSION);
      hello.setName(w.name);
      hello.setCores(1);
      hello.setMemoryBytes(uint64_t(1) << 30);
      send(w, message);
    }
  }

  void run() {
    std::vector<zmq::pollitem_t> items(workers_.size());
    for (size_t i = 0; i < workers_.size(); ++i) items[i] = {workers_[i].socket->handle(), 0, ZMQ_POLLIN, 0};
    while (!stopRequested) {
      try {
        zmq::poll(items.data(), items.size(), std::chrono::milliseconds(100));
      } catch (const zmq::error_t& e) {
        if (e.num() != EINTR) throw;
      }
      const int64_t now = steadyNs();
      for (size_t i = 0; i < workers_.size(); ++i) {
        SimulatedWorker& w = workers_[i];
        if (items[i].revents & ZMQ_POLLIN) drain(w);
        if (w.welcomed && now - w.lastSentNs >= w.heartbeatNs) {
          capnp::MallocMessageBuilder message;
          message.initRoot<wire::Envelope>().initHeartbeat().setProgress(w.progress);
          send(w, message);
        }
      }
    }
    for (SimulatedWorker& w : workers_) {
      capnp::MallocMessageBuilder message;
      message.initRoot<wire::Envelope>().setGoodbye();
      send(w, message);
    }
  }

  void writeReport() const {
    nlohmann::json totals = {{"results", report_.tally.results},
                             {"emitted", report_.tally.emitted},
                             {"photons_handed_on", report_.tally.photonsHandedOn},
                             {"deposit_records", report_.tally.depositRecords},
                             {"region_records", report_.tally.regionRecords},
                             {"camera_rays", report_.tally.cameraRays},
                             {"rays_handed_on", report_.tally.raysHandedOn},
                             {"bytes_sent", report_.bytesSent},
                             {"bytes_received", report_.bytesReceived},
                             {"assigns", report_.assigns},
                             {"photon_fetches", report_.photonFetches},
                             {"errors", report_.errors},
                             {"cpu_s", processCpuSeconds()},
                             {"photon_phase_bytes", report_.phaseBytes[0]},
                             {"render_phase_bytes", report_.phaseBytes[1]}};
    std::ofstream out(options_.report);
    out << totals.dump() << "\n";
    for (const auto& [sent, latency] : report_.results) out << sent << ' ' << latency << '\n';
    if (!out) throw std::runtime_error("cannot write " + options_.report);
  }

 private:
  // `phase`: the phase whose bytes these are (-1: none, as a heartbeat's).
  void send(SimulatedWorker& w, capnp::MessageBuilder& message, net::Encoding encoding = net::Encoding::Packed,
            int phase = -1) {
    zmq::message_t frame = net::encode(message, encoding);
    report_.bytesSent += int64_t(frame.size());
    if (phase >= 0) report_.phaseBytes[phase] += int64_t(frame.size());
    (void)w.socket->send(frame, zmq::send_flags::dontwait);
    w.lastSentNs = steadyNs();
  }

  void drain(SimulatedWorker& w) {
    zmq::message_t frame;
    while (w.socket->recv(frame, zmq::recv_flags::dontwait)) {
      report_.bytesReceived += int64_t(frame.size());
      const auto bytes = int64_t(frame.size());
      auto decoded = std::make_unique<net::Decoded>(std::move(frame));
      const auto envelope = decoded->envelope();
      if (envelope.which() == wire::Envelope::ASSIGN)
        report_.phaseBytes[envelope.getAssign().getPhase() == wire::Phase::RENDER ? 1 : 0] += bytes;
      else if (envelope.which() == wire::Envelope::PHOTONS)
        report_.phaseBytes[1] += bytes;
      switch (envelope.which()) {
        case wire::Envelope::WELCOME: {
          w.welcomed = true;
          w.heartbeatNs = int64_t(std::max<uint32_t>(100, envelope.getWelcome().getHeartbeatMs())) * 1'000'000;
          capnp::MallocMessageBuilder ready;
          ready.initRoot<wire::Envelope>().setReady();
          send(w, ready);
          break;
        }
        case wire::Envelope::ASSIGN: onAssign(w, std::move(decoded)); break;
        case wire::Envelope::PHOTONS: onPhotons(w); break;
        case wire::Envelope::HEARTBEAT: break;
        case wire::Envelope::ERROR: ++report_.errors; break;
        default: break;
      }
      frame = zmq::message_t();
    }
  }

  void onAssign(SimulatedWorker& w, std::unique_ptr<net::Decoded> decoded) {
    ++report_.assigns;
    // Every Result since the last Assign waited until now for this one.
    const int64_t now = steadyNs();
    for (const size_t sample : w.resultsAwaitingAssign) report_.results[sample].second = now - report_.results[sample].first;
    w.resultsAwaitingAssign.clear();
    const auto assign = decoded->envelope().getAssign();
    // A render lease reads its cell's photons: fetched once per cell, as a
    // worker's cache keeps them.
    if (assign.getPhase() == wire::Phase::RENDER) {
      const std::pair<uint64_t, uint32_t> key{assign.getPhotonJob(), assign.getCell()};
      if (!w.photonsHeld.count(key) || !w.waiting.empty()) {
        w.waiting.push_back(std::move(decoded));
        fetchNext(w);
        return;
      }
    }
    answer(w, assign);
  }

  void fetchNext(SimulatedWorker& w) {
    while (!w.fetching && !w.waiting.empty()) {
      const auto assign = w.waiting.front()->envelope().getAssign();
      const std::pair<uint64_t, uint32_t> key{assign.getPhotonJob(), assign.getCell()};
      if (w.photonsHeld.count(key)) {
        answer(w, assign);
        w.waiting.pop_front();
        continue;
      }
      capnp::MallocMessageBuilder message;
      auto fetch = message.initRoot<wire::Envelope>().initFetchPhotons();
      fetch.setJob(assign.getJob());
      fetch.setCell(assign.getCell());
      send(w, message, net::Encoding::Packed, 1);
      ++report_.photonFetches;
      w.fetching = key;
    }
  }

  void onPhotons(SimulatedWorker& w) {
    if (!w.fetching) return;
    w.photonsHeld.insert(*w.fetching);
    w.fetching.reset();
    fetchNext(w);
  }

  void answer(SimulatedWorker& w, wire::Assign::Reader assign) {
    if (!neighbours_) neighbours_.emplace(SceneStore::open(assign.getSpec().getStore().cStr()));
    SimulatedResult result = simulateResult(assign, options_.shape, *neighbours_, options_.depositRegions);
    send(w, *result.message, net::Encoding::Flat, assign.getPhase() == wire::Phase::RENDER ? 1 : 0);
    report_.tally.add(result.tally);
    ++w.progress;
    w.resultsAwaitingAssign.push_back(report_.results.size());
    report_.results.emplace_back(w.lastSentNs, -1);
  }

  const SimulatedWorkersOptions& options_;
  zmq::context_t context_;
  std::vector<SimulatedWorker> workers_;
  std::optional<CellNeighbours> neighbours_;
  SimulatedReport report_;
};
}  // namespace

void SimulatedReport::add(const SimulatedReport& o) {
  tally.add(o.tally);
  bytesSent += o.bytesSent, bytesReceived += o.bytesReceived, assigns += o.assigns;
  photonFetches += o.photonFetches, errors += o.errors, cpuSeconds += o.cpuSeconds;
  phaseBytes[0] += o.phaseBytes[0], phaseBytes[1] += o.phaseBytes[1];
  results.insert(results.end(), o.results.begin(), o.results.end());
}

int runSimulatedWorkers(const SimulatedWorkersOptions& options) {
  signal(SIGTERM, onStop);
  signal(SIGINT, onStop);
  // A bench killed outright (SIGKILL) leaves no one to stop these workers:
  // they stop with it.
  ::prctl(PR_SET_PDEATHSIG, SIGTERM);
  WorkerProcess process(options);
  process.run();
  process.writeReport();
  return 0;
}

SimulatedReport readSimulatedReport(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  if (!std::getline(in, line)) throw std::runtime_error(fmt::format("{}: missing or empty", path));
  SimulatedReport r;
  try {
    const auto t = nlohmann::json::parse(line);
    r.tally.results = t.at("results"), r.tally.emitted = t.at("emitted");
    r.tally.photonsHandedOn = t.at("photons_handed_on"), r.tally.depositRecords = t.at("deposit_records");
    r.tally.regionRecords = t.at("region_records"), r.tally.cameraRays = t.at("camera_rays");
    r.tally.raysHandedOn = t.at("rays_handed_on");
    r.bytesSent = t.at("bytes_sent"), r.bytesReceived = t.at("bytes_received"), r.assigns = t.at("assigns");
    r.photonFetches = t.at("photon_fetches"), r.errors = t.at("errors"), r.cpuSeconds = t.at("cpu_s");
    r.phaseBytes[0] = t.at("photon_phase_bytes"), r.phaseBytes[1] = t.at("render_phase_bytes");
  } catch (const std::exception& e) {
    throw std::runtime_error(fmt::format("{}:1: {}", path, e.what()));
  }
  int64_t sent = 0, latency = 0;
  while (in >> sent >> latency) r.results.emplace_back(sent, latency);
  return r;
}

}  // namespace portico::cli
