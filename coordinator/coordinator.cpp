#include "coordinator/coordinator.h"

#include <capnp/message.h>
#include <fmt/chrono.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <set>

#include "common/job/worker_tags.h"
#include "common/net/endpoint_scope.h"
#include "common/net/job_spec_wire.h"
#include "common/scene/store/store_file_names.h"
#include "common/transport/photon_record.h"
#include "common/transport/trace_counters.h"
#include "common/util/atomic_file.h"
#include "common/util/output_path.h"
#include "common/util/process_memory.h"
#include "coordinator/analysis_sensors.h"
#include "coordinator/assign_encoder.h"
#include "coordinator/cell_choice.h"
#include "coordinator/file_server.h"
#include "coordinator/job_limits.h"
#include "coordinator/job_planner.h"
#include "coordinator/job_activity.h"
#include "coordinator/job_report.h"
#include "coordinator/peer_rights.h"
#include "coordinator/photon_reuse.h"
#include "coordinator/render_passes.h"
#include "coordinator/result_applier.h"
#include "coordinator/result_check.h"

namespace portico {

int64_t nowMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

namespace {
constexpr uint32_t kLeaseOwnCell = 0xffffffff;   // Failure.failedCell's default

// A Submit's or PriorityRequest's priority, within the documented range.
int checkedPriority(int64_t priority) {
  if (priority < limits::kMinPriority || priority > limits::kMaxPriority)
    throw std::invalid_argument(fmt::format("priority {} is out of range: expected a whole number from {} to {}",
                                            priority, limits::kMinPriority, limits::kMaxPriority));
  return int(priority);
}

// Wall-clock for records that outlive the process (job creation, phases).
int64_t wallMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// A wall-clock time in status and errors: "2026-12-07 18:02:11 UTC".
std::string utcTime(int64_t wallMs) {
  return fmt::format("{:%Y-%m-%d %H:%M:%S} UTC", fmt::gmtime(std::time_t(wallMs / 1000)));
}

// Checked before jobs.db is opened: a refused start leaves nothing behind.
CoordinatorOptions checkedOptions(CoordinatorOptions options) {
  requireKeysBeyondLoopback(options.listen, options.keysDirectory);
  return options;
}

std::string shortId(const std::string& identity) {
  std::string hex;
  for (unsigned char c : identity) hex += fmt::format("{:02x}", c);
  return hex;
}
}  // namespace

Coordinator::Coordinator(CoordinatorOptions options)
    : options_(checkedOptions(std::move(options))),
      store_(options_.database),
      zmq_(1),
      router_(zmq_, zmq::socket_type::router),
      maxFrameBytes_(net::maxCoordinatorFrameBytes(options_.maxLeaseWork)) {
  router_.set(zmq::sockopt::linger, 0);
  router_.set(zmq::sockopt::router_mandatory, false);
  if (net::isIpv6Endpoint(options_.listen)) router_.set(zmq::sockopt::ipv6, true);
  security_ = std::make_unique<RouterSecurity>(zmq_, router_, options_.listen, options_.keysDirectory, maxFrameBytes_);
  router_.bind(bindableEndpoint(options_.listen));
  endpoint_ = router_.get(zmq::sockopt::last_endpoint);
  if (!options_.endpointFile.empty()) {
    writeFileAtomically(options_.endpointFile, endpoint_ + "\n");
  }
  const int requeued = store_.requeueAllOpenLeases();
  const auto active = store_.jobs(true);
  spdlog::info("coordinator listening on {} (db {}, {} active jobs, {} leases requeued)", endpoint_,
               options_.database, active.size(), requeued);
  // Photon tables written by an older portico in another record format
  // cannot be read: such a job's photon pass runs again (same photons).
  for (const JobRecord& job : active)
    if (job.photonRecordBytes != int(sizeof(PhotonRecord)))
      restartPhotonPass(job.id, fmt::format("its photon tables hold {}-byte records of an older portico, not {}",
                                            job.photonRecordBytes, sizeof(PhotonRecord)));
  // A coordinator killed between a phase's last result and the next phase
  // resumes here.
  for (const JobRecord& job : active) advanceIfPhaseDone(job.id);
}

Coordinator::~Coordinator() = default;

void Coordinator::run() {
  while (!stopping_) {
    zmq::pollitem_t items[] = {{router_.handle(), 0, ZMQ_POLLIN, 0}};
    try {
      zmq::poll(items, 1, std::chrono::milliseconds(100));
    } catch (const zmq::error_t& e) {
      if (e.num() != EINTR) throw;   // a signal: the loop condition decides
    }
    runRound();
  }
  // Replies still queued (a Shutdown's acknowledgement) get a moment to leave.
  router_.set(zmq::sockopt::linger, 1000);
  spdlog::info("coordinator stopping");
}

// Group commit. Two commits per Result (the worker's next lease, then the
// Result), each writing its pages to the WAL, cost a third of the
// coordinator's CPU in a photon pass, and at the end of a pass, where
// Results of a few photons each arrive faster than they are committed,
// the workers would wait for the coordinator. A round takes all that
// has arrived and makes one or two transactions of it, whatever the number
// of messages: the leases refilling the slots that the Results freed, when
// a worker would otherwise run out of work meanwhile (WorkerInfo::runsShort),
// then the messages themselves with the timers and the scheduling (each
// handler's own transaction nests in it as a savepoint, so a rejected
// Result still leaves nothing). Each commits before what it sends leaves:
// no lease, reply or job id goes out before what it refers to is durable.
void Coordinator::runRound() {
  // Drain what arrived.
  struct Incoming {
    std::string identity;
    size_t bytes = 0;
    std::unique_ptr<net::Decoded> message;
    std::optional<net::Peer> peer;   // what the peer was admitted as, and who it is
  };
  std::vector<Incoming> arrived;
  for (int drained = 0; drained < 256; ++drained) {
    zmq::message_t identity, frame;
    if (!router_.recv(identity, zmq::recv_flags::dontwait)) break;
    std::string id(static_cast<const char*>(identity.data()), identity.size());
    bool garbage = false;
    if (!identity.more()) garbage = true;
    else {
      (void)router_.recv(frame);
      // A peer that sends more than one frame is not speaking our protocol.
      while (frame.more()) {
        zmq::message_t extra;
        (void)router_.recv(extra);
        garbage = true;
        frame.move(extra);
      }
    }
    if (garbage) {
      spdlog::warn("dropped a message from {}: unexpected frame layout", shortId(id));
      continue;
    }
    try {
      const size_t bytes = frame.size();
      auto peer = security_->peerOf(frame);
      arrived.push_back({id, bytes, std::make_unique<net::Decoded>(std::move(frame)), std::move(peer)});
    } catch (const kj::Exception& e) {
      spdlog::warn("dropped a malformed message from {}: {}", shortId(id), e.getDescription().cStr());
    } catch (const std::exception& e) {
      spdlog::warn("dropped a message from {}: {}", shortId(id), e.what());
    }
  }

  // First the leases of the workers whose Results just came: they go out
  // before the Results are applied (photon files, queues, counters: the
  // coordinator's longest step), so that the workers trace meanwhile
  // instead of waiting for it. A new lease cannot hold these Results'
  // crossings, not queued yet; any order of leases gives the same bits.
  bool refillFirst = false;
  for (const Incoming& in : arrived) {
    auto envelope = in.message->envelope();
    if (envelope.which() != wire::Envelope::RESULT || refusalFor(roleOf(in.peer), envelope.which())) continue;
    if (auto worker = workers_.find(in.identity); worker != workers_.end()) {
      const uint64_t lease = envelope.getResult().getLease();
      int64_t workerMicros = 0, loadMicros = 0, trianglesLoaded = 0;
      for (auto counter : envelope.getResult().getCounters()) {
        const std::string_view name = counter.getName().cStr();
        if (name == kLeaseTimeCounter) workerMicros = counter.getValue();
        else if (name == kLoadTimeCounter) loadMicros = counter.getValue();
        else if (name == kTrianglesLoadedCounter) trianglesLoaded = counter.getValue();
      }
      worker->second.recordLease(lease, wallMs(), workerMicros);
      ++worker->second.leasesDone;
      worker->second.recordLoads(trianglesLoaded, loadMicros);
      if (auto sent = worker->second.leases.find(lease); sent != worker->second.leases.end()) {
        arrivedLeases_[lease] = sent->second;
        worker->second.leases.erase(sent);
      }
      refillFirst = refillFirst || worker->second.runsShort();
    }
  }
  // A worker still holding a lease of some length traces it while the
  // Results are applied, and its next lease goes with the round's own
  // commit: one commit per round, not two.
  if (refillFirst) inRound([&] { dispatch(); });

  // A wake-up with nothing to do (no message, no timer due, no lease to
  // hand out) opens no transaction: the loop wakes ten times a second.
  if (arrived.empty() && !requeueOwed_ && nowMs() - lastHeartbeatMs_ < options_.heartbeatMs && !leaseWanted()) {
    security_->logConnectionEvents();
    return;
  }
  size_t handled = 0;
  bool requeued = false;
  const bool committed = inRound([&] {
    for (; handled < arrived.size(); ++handled)
      handle(arrived[handled].identity, *arrived[handled].message, arrived[handled].bytes, arrived[handled].peer);
    // What a failed round's undo could not write. After the messages: the
    // leases whose Results just arrived are no longer counted as traced.
    if (requeueOwed_) {
      requeueUntracedLeases();
      requeued = true;
    }
    security_->logConnectionEvents();
    const int64_t now = nowMs();
    if (now - lastHeartbeatMs_ >= options_.heartbeatMs) {
      lastHeartbeatMs_ = now;
      checkLiveness();
      checkLeaseProgress();
      checkStores();
      for (auto& [identity, worker] : workers_) {
        capnp::MallocMessageBuilder message;
        message.initRoot<wire::Envelope>().initHeartbeat();
        send(identity, message);
      }
    }
    dispatch();
  });
  if (committed && requeued) requeueOwed_ = false;
  // A write the disk refused undid the round at message `handled` (its work
  // requeued): the messages after it are handled one by one, so that status
  // requests, heartbeats and file fetches are answered even on a full disk.
  if (!committed)
    for (size_t i = handled + 1; i < arrived.size(); ++i)
      handle(arrived[i].identity, *arrived[i].message, arrived[i].bytes, arrived[i].peer);
  arrivedLeases_.clear();   // a dropped Result is not logged
}

bool Coordinator::inRound(const std::function<void()>& work) {
  inRound_ = true;
  outbox_.clear();
  roundLeases_.clear();
  roundResults_.clear();
  bool committed = false;
  try {
    sql::Transaction round(store_.database());
    work();
    if (options_.failCommitsEvery > 0 && !roundResults_.empty() && ++roundTransactions_ % options_.failCommitsEvery == 0)
      throw std::runtime_error("fault injection: this commit fails");
    round.commit();
    committed = true;
  } catch (const std::exception& e) {
    if (isDiskTrouble(e))
      noteDiskTrouble(e.what());
    else
      spdlog::error("could not commit what the coordinator just did ({}): its leases are taken back and its "
                    "results requeued",
                    e.what());
  }
  inRound_ = false;
  if (!committed) {
    undoRound();
    return false;
  }
  if (diskBackoffMs_ > 0 && !roundResults_.empty()) {
    spdlog::info("jobs.db and its files can be written again ({} rounds undone in all); leasing resumes",
                 diskFailures_);
    diskBackoffMs_ = 0;
    diskFailures_ = 0;
    diskPausedUntilMs_ = 0;
    diskRoundsUndone_ = 0;
    diskTroubleWhat_.clear();
  }
  for (Outgoing& out : outbox_) transmit(out.identity, out.frame);
  outbox_.clear();
  try {
    store_.reclaimBatchFiles();
  } catch (const std::exception& e) {
    spdlog::warn("could not delete consumed batch files ({}); trying again after the next commit", e.what());
  }
  return true;
}

// The round's transaction rolled back (a full disk): jobs.db is as it was
// before the round, and the coordinator's memory is brought back in line
// with it. The leases the round opened never were: they are not sent, and
// their workers' slots are free again; a job it created never was: its id
// is not sent (the client's request times out). Then every lease jobs.db
// holds open that no worker is known to trace (those whose Results the
// round applied, those of workers it released) goes back to the queue, to
// be traced again: the same bits. Replies that read what was committed
// before the round (photons, files, status, welcomes) still go out: a
// worker waiting for its photons would otherwise wait forever.
void Coordinator::undoRound() {
  jobs_.clear();   // a cache: reloaded from jobs.db on demand
  for (const auto& [identity, lease] : roundLeases_)
    if (auto worker = workers_.find(identity); worker != workers_.end()) worker->second.leases.erase(lease);
  try {
    sql::Transaction tx(store_.database());
    requeueUntracedLeases();
    tx.commit();
    requeueOwed_ = false;
  } catch (const std::exception& e) {
    // A full disk refuses this too: the next round that commits does it.
    requeueOwed_ = true;
    if (!isDiskTrouble(e))
      spdlog::error("could not requeue the leases lost with it either ({}); the next round tries again", e.what());
  }
  for (Outgoing& out : outbox_)
    if (!out.refersToRound) transmit(out.identity, out.frame);
  outbox_.clear();
}

void Coordinator::requeueUntracedLeases() {
  for (const LeaseRecord& lease : store_.openLeases()) {
    auto worker = workers_.find(lease.worker);
    if (worker == workers_.end() || !worker->second.leases.count(lease.id)) {
      store_.requeueLease(lease.id);
      depositRegions_.erase(lease.id);
    }
  }
}

bool Coordinator::isDiskTrouble(const std::exception& e) {
  if (dynamic_cast<const DiskWriteError*>(&e)) return true;
  const auto* sqlite = dynamic_cast<const sql::Error*>(&e);
  return sqlite && sqlite->diskTrouble();
}

// A full disk fails every round that writes: without a pause the
// coordinator would lease, fail and log twenty times a second. Leasing
// waits 0.25 s, then twice as long after each failed round (at most 8 s);
// one line every 10 s counts the rounds undone meanwhile. Nothing is lost:
// an undone round's leases and Results go back to the queue, to be traced
// again with the same bits, and none counts against a cell.
void Coordinator::noteDiskTrouble(const std::string& what) {
  diskBackoffMs_ = std::clamp<int64_t>(diskBackoffMs_ * 2, 250, 8000);
  diskPausedUntilMs_ = nowMs() + diskBackoffMs_;
  ++diskFailures_;
  if (diskRoundsUndone_++ == 0) diskTroubleSinceMs_ = wallMs();
  diskTroubleWhat_ = what;
  if (diskFailures_ == 1 || nowMs() - diskLoggedMs_ >= 10000) {
    diskLoggedMs_ = nowMs();
    spdlog::error("cannot write jobs.db or its files ({}); nothing is lost: the round is undone, its work "
                  "requeued; leasing resumes in {:.2f} s ({} rounds undone so far)",
                  what, diskBackoffMs_ / 1000.0, diskFailures_);
  }
}

void Coordinator::handle(const std::string& identity, const net::Decoded& decoded, size_t bytes,
                         const std::optional<net::Peer>& peer) {
  const std::optional<net::Role> role = roleOf(peer);
  const int64_t started = nowMs();
  struct SlowLog {
    int64_t started;
    size_t bytes;
    ~SlowLog() {
      if (nowMs() - started > 20) spdlog::debug("handling a {} byte message took {} ms", bytes, nowMs() - started);
    }
  } slowLog{started, bytes};
  try {
    auto envelope = decoded.envelope();
    // A message its sender's role may not send is answered and logged, never acted on.
    if (const auto refusal = refusalFor(role, envelope.which())) {
      if (const auto leftOut = refusals_.admit(fmt::format("{} {}", shortId(identity), int(envelope.which()))))
        spdlog::warn("{} (from {}){}", *refusal, shortId(identity), leftOutSuffix(*leftOut));
      sendError(identity, *refusal);
      return;
    }
    if (auto it = workers_.find(identity); it != workers_.end()) it->second.lastSeenMs = nowMs();
    switch (envelope.which()) {
      case wire::Envelope::HELLO: onHello(identity, envelope.getHello()); break;
      case wire::Envelope::HEARTBEAT: {
        auto worker = workers_.find(identity);
        // A worker of this coordinator's previous run: it rejoins at once
        // instead of waiting out its liveness timeout.
        if (worker == workers_.end()) {
          if (role != net::Role::Client) sendError(identity, net::kUnknownWorkerError);
          break;
        }
        const auto beat = envelope.getHeartbeat();
        worker->second.tracingLease = beat.getTracingLease();
        if (beat.getProgress() != worker->second.progress) {
          worker->second.progress = beat.getProgress();
          noteProgress(worker->second);
        }
        break;
      }
      case wire::Envelope::READY: onReady(identity); break;
      case wire::Envelope::RESULT: onResult(identity, envelope.getResult()); break;
      case wire::Envelope::FAILURE: onFailure(identity, envelope.getFailure()); break;
      case wire::Envelope::FETCH_PHOTONS: onFetchPhotons(identity, envelope.getFetchPhotons()); break;
      case wire::Envelope::FETCH_FILE: onFetchFile(identity, envelope.getFetchFile()); break;
      case wire::Envelope::FETCH_IMAGE: onFetchImage(identity, peer, envelope.getFetchImage()); break;
      case wire::Envelope::SUBMIT: onSubmit(identity, peer, envelope.getSubmit()); break;
      case wire::Envelope::STATUS: onStatus(identity, peer, envelope.getStatus()); break;
      case wire::Envelope::CANCEL: onCancel(identity, peer, envelope.getCancel()); break;
      case wire::Envelope::JOB_DETAIL: onJobDetail(identity, peer, envelope.getJobDetail()); break;
      case wire::Envelope::FETCH_PREVIEW: onFetchPreview(identity, peer, envelope.getFetchPreview()); break;
      case wire::Envelope::PRIORITY: onPriority(identity, peer, envelope.getPriority()); break;
      case wire::Envelope::GOODBYE: onGoodbye(identity); break;
      case wire::Envelope::SHUTDOWN: {
        spdlog::info("shutdown requested by {}", shortId(identity));
        stopping_ = true;
        // Acknowledged, so that `portico shutdown` tells a stop from a refusal or silence.
        capnp::MallocMessageBuilder ack;
        ack.initRoot<wire::Envelope>().setShutdown();
        send(identity, ack);
        break;
      }
      default:
        spdlog::warn("dropped a message from {}: unexpected type {}", shortId(identity), int(envelope.which()));
    }
    // What only a worker whose leases move sends; noted once handled, so
    // that the time the coordinator took to answer a fetch is not the worker's.
    switch (envelope.which()) {
      case wire::Envelope::RESULT:
      case wire::Envelope::FAILURE:
      case wire::Envelope::FETCH_PHOTONS:
      case wire::Envelope::FETCH_FILE:
        if (auto worker = workers_.find(identity); worker != workers_.end()) noteProgress(worker->second);
        break;
      default: break;
    }
  } catch (const kj::Exception& e) {
    spdlog::warn("dropped a malformed message from {}: {}", shortId(identity), e.getDescription().cStr());
  } catch (const std::exception& e) {
    if (isDiskTrouble(e)) {
      if (inRound_) throw;   // the whole round is undone (inRound), its work requeued
      ++diskFailures_;       // a message handled after such a round: counted, logged with them
      requeueOwed_ = true;   // a lease it let go of may still be open in jobs.db
      return;
    }
    spdlog::warn("dropped a message from {}: {}", shortId(identity), e.what());
  }
}

void Coordinator::send(const std::string& identity, capnp::MallocMessageBuilder& message, net::Encoding encoding) {
  zmq::message_t frame = net::encode(message, encoding);
  if (inRound_) {
    const auto type = message.getRoot<wire::Envelope>().which();
    outbox_.push_back({identity, std::move(frame),
                       type == wire::Envelope::ASSIGN || type == wire::Envelope::SUBMIT_REPLY});
    return;
  }
  transmit(identity, frame);
}

void Coordinator::transmit(const std::string& identity, zmq::message_t& frame) {
  zmq::message_t id(identity.data(), identity.size());
  router_.send(id, zmq::send_flags::sndmore);
  router_.send(frame, zmq::send_flags::none);
}

void Coordinator::sendError(const std::string& identity, const std::string& error) {
  capnp::MallocMessageBuilder message;
  message.initRoot<wire::Envelope>().setError(error);
  send(identity, message);
}

void Coordinator::onHello(const std::string& identity, wire::Hello::Reader hello) {
  if (hello.getVersion() != wire::PROTOCOL_VERSION) {
    spdlog::warn("refused worker {}: protocol version {} (this coordinator speaks {})", hello.getName().cStr(),
                 hello.getVersion(), wire::PROTOCOL_VERSION);
    sendError(identity, fmt::format("protocol version {} is not supported (coordinator speaks {})",
                                    hello.getVersion(), wire::PROTOCOL_VERSION));
    releaseWorker(identity, "dropped: wrong protocol version");   // if it had joined before
    return;
  }
  std::vector<std::string> tags;
  for (const auto tag : hello.getTags()) tags.emplace_back(tag.cStr());
  try {
    tags = normalizedTags(std::move(tags), "Hello");
  } catch (const std::invalid_argument& e) {
    spdlog::warn("refused worker {}: {}", hello.getName().cStr(), e.what());
    sendError(identity, e.what());
    releaseWorker(identity, "dropped: bad tags");
    return;
  }
  WorkerInfo& worker = workers_[identity];
  worker.identity = identity;
  worker.name = hello.getName();
  worker.tags = std::move(tags);
  worker.cores = hello.getCores();
  worker.memoryBytes = hello.getMemoryBytes();
  worker.cells.setBudget(worker.memoryBytes);
  worker.lastSeenMs = nowMs();
  spdlog::info("worker {} joined ({} cores, {} MiB budget{}{})", worker.name, worker.cores, worker.memoryBytes >> 20,
               worker.tags.empty() ? "" : ", tags ", joinTags(worker.tags));
  capnp::MallocMessageBuilder message;
  auto welcome = message.initRoot<wire::Envelope>().initWelcome();
  welcome.setVersion(wire::PROTOCOL_VERSION);
  welcome.setHeartbeatMs(options_.heartbeatMs);
  welcome.setMaxFrameBytes(maxFrameBytes_);
  send(identity, message);
}

void Coordinator::onReady(const std::string& identity) {
  auto it = workers_.find(identity);
  if (it == workers_.end()) {
    sendError(identity, net::kUnknownWorkerError);
    return;
  }
  it->second.ready = true;
}

Coordinator::JobContext& Coordinator::context(uint64_t job) {
  auto it = jobs_.find(job);
  if (it != jobs_.end()) return it->second;
  auto record = store_.job(job);
  if (!record) throw std::runtime_error(fmt::format("job {} does not exist", job));
  JobContext context;
  net::PackedReader reader(record->spec.data(), record->spec.size());
  const JobSettings stored = jobSettingsFromWire(reader.root<wire::JobSpec>());
  context.scene = std::make_unique<SceneStore>(SceneStore::open(stored.store));
  // Stored resolved; resolving again keeps a job that a coordinator with
  // fewer automatic values stored complete too.
  context.spec = std::make_unique<capnp::MallocMessageBuilder>();
  toWire(resolveJobSettings(stored, *context.scene), context.spec->initRoot<wire::JobSpec>());
  context.photonJob = record->photonJob();
  context.renderPass = loadRenderProgress(store_.database(), job).passesStarted - 1;
  return jobs_.emplace(job, std::move(context)).first->second;
}

bool Coordinator::leaseWanted() {
  if (nowMs() < diskPausedUntilMs_) return false;
  if (std::none_of(workers_.begin(), workers_.end(), [](const auto& w) { return w.second.wantsLease(); }))
    return false;
  return !store_.pendingCells(1).empty();
}

void Coordinator::dispatch() {
  if (nowMs() < diskPausedUntilMs_) return;   // the disk refused the last round's writes
  for (auto& [identity, worker] : workers_) {
    if (!refusalsByWorker_.empty() && sidelined(worker)) continue;
    for (size_t k = 0; k < WorkerInfo::kMostLeasesInFlight && worker.wantsLease(); ++k) {
      const Assignment assigned = assignWork(worker);
      if (assigned == Assignment::NothingLeft) return;
      if (assigned == Assignment::NothingForThisWorker) break;
    }
  }
}

Coordinator::Assignment Coordinator::assignWork(WorkerInfo& worker) {
  // Only the jobs whose required tags the worker has (worker pools): what
  // it cannot take may still be another worker's.
  bool othersWork = false;
  auto candidates = store_.pendingCells(kLeaseCandidates, [&](const std::vector<std::string>& requiredTags) {
    const bool mine = hasAllTags(worker.tags, requiredTags);
    othersWork = othersWork || !mine;
    return mine;
  });
  const Assignment nothing = othersWork ? Assignment::NothingForThisWorker : Assignment::NothingLeft;
  // Cells whose last lease failed or was lost wait their back-off out.
  if (!retries_.empty()) {
    const int64_t now = nowMs();
    std::erase_if(candidates, [&](const PendingCell& c) {
      const auto retry = retries_.find({c.job, c.cell});
      return retry != retries_.end() && retry->second.notBeforeMs > now;
    });
  }
  if (candidates.empty()) return nothing;
  // Cells one of whose Results from this worker was refused go to others.
  if (!refusedResults_.empty()) {
    std::erase_if(candidates, [&](const PendingCell& c) { return leftToOthers(worker, c.job, c.cell); });
    if (candidates.empty()) return Assignment::NothingForThisWorker;
  }
  // A job whose store could not be loaded waits for it (checkStores).
  if (!storeTrouble_.empty()) {
    std::erase_if(candidates,
                  [&](const PendingCell& c) { return storeTrouble_.count(c.job) && !jobs_.count(c.job); });
    if (candidates.empty()) return nothing;
  }
  JobContext* job;
  try {
    job = &context(candidates.front().job);
  } catch (const std::exception& e) {
    if (const auto directory = storeDirectoryOf(candidates.front().job);
        directory && ::access((*directory + "/scene.db").c_str(), R_OK) != 0)
      noteStoreTrouble(candidates.front().job, fmt::format("{}/scene.db: {}", *directory, std::strerror(errno)));
    else
      failJob(candidates.front().job, e.what());
    return Assignment::Assigned;
  }
  const auto& cells = job->scene->cells();
  const PendingCell* chosen = chooseCell(candidates, cells, worker, workers_);
  if (!chosen) return Assignment::NothingForThisWorker;
  const auto cachedBytes = [&](uint32_t cell) { return cachedBytesOf(cells, cell); };
  std::vector<QueuedBatch> batches;
  std::vector<std::pair<uint32_t, std::vector<QueuedBatch>>> moreCells;
  LeaseRecord opened;
  int64_t leaseWork = 0;
  std::optional<DepositRegionGrant> region;
  try {
    sql::Transaction tx(store_.database());
    opened = store_.openLease(*chosen, worker.identity, worker.nextLeaseWork(options_.maxLeaseWork), wallMs(), batches);
    for (const QueuedBatch& batch : batches) leaseWork += batch.work;
    if (opened.id)
      leaseWork = addMoreCells(
          candidates, *chosen, cells, worker, workers_, leaseWork,
          [&](const PendingCell& c) { return failedCells_.count({c.job, c.cell}) != 0; },
          [&](const PendingCell& c, int64_t maxWork) {
            std::vector<QueuedBatch> extra;
            const int64_t added = store_.addToLease(opened.id, c, maxWork, extra);
            if (extra.empty()) return int64_t(-1);
            moreCells.emplace_back(c.cell, std::move(extra));
            return added;
          });
    if (opened.id && chosen->phase == 0 && options_.depositRegions) {
      DepositRegionGrant grant;
      for (size_t i = 0; i < grant.nonce.size(); i += 8) {
        const uint64_t random = nonceSource_();
        for (size_t b = 0; b < 8; ++b) grant.nonce[i + b] = uint8_t(random >> (8 * b));
      }
      grant.size = depositRegionBytes(leaseWork, 1 + moreCells.size());
      grant.offset = store_.reserveDepositRegion(chosen->job, grant.size,
                                                 deposit_region::encodeHead(chosen->job, opened.id, grant.nonce));
      region = grant;
    }
    tx.commit();
  } catch (const DamagedFileError& e) {
    // Queued rays lost under a committed row (an operating-system crash, or
    // someone wrote to the file): nothing was leased. The passes are
    // deterministic, so the job starts over rather than fail.
    restartPhotonPass(chosen->job, e.what());
    return Assignment::Assigned;
  }
  const uint64_t lease = opened.id;
  if (!lease) return Assignment::Assigned;
  AssignContents contents;
  contents.lease = opened;
  contents.spec = job->reader();
  contents.photonJob = job->photonJob;
  contents.renderPass = job->renderPass;
  contents.cellWork = chosen->work;
  contents.batches = &batches;
  contents.moreCells = &moreCells;
  if (region) {
    contents.region = AssignContents::Region{std::filesystem::absolute(store_.photonFile(chosen->job)).string(),
                                             region->offset, region->size};
    depositRegions_[lease] = *region;
  }
  capnp::MallocMessageBuilder message;
  const LeaseExpectation expected = encodeAssign(contents, message);
  send(worker.identity, message, net::Encoding::Flat);   // rays: packing gains little, costs a pass
  ++leasesSent_;
  if (worker.leases.empty()) worker.progressMs = nowMs();   // its lease clock starts with its first lease
  WorkerInfo::LeaseInFlight inFlight{wallMs(), leaseWork, {}, expected};
  inFlight.job = chosen->job, inFlight.cell = chosen->cell, inFlight.phase = opened.phase;
  for (const auto& [cell, extra] : moreCells) {
    int64_t work = 0;
    for (const QueuedBatch& batch : extra) work += batch.work;
    inFlight.moreCellWork.emplace_back(cell, work);
  }
  worker.leases.emplace(lease, std::move(inFlight));
  if (inRound_) roundLeases_.emplace_back(worker.identity, lease);
  for (const auto& [cell, unused] : moreCells) worker.cells.use(chosen->job, cell, cachedBytes(cell));
  worker.cells.use(chosen->job, chosen->cell, cachedBytes(chosen->cell));
  if (opened.attempt > 1)
    spdlog::info("lease {} -> {}: job {} cell {} phase {}, attempt {} ({} batches, {} more cells)", lease,
                 worker.name, chosen->job, chosen->cell, chosen->phase, opened.attempt, batches.size(),
                 moreCells.size());
  else
    spdlog::debug("lease {} -> {}: job {} cell {} phase {} ({} batches, {} more cells, work {}; it holds {} cells)", lease,
                  worker.name, chosen->job, chosen->cell, chosen->phase, batches.size(), moreCells.size(), leaseWork,
                  worker.cells.size());
  return Assignment::Assigned;
}

void Coordinator::onResult(const std::string& identity, wire::Result::Reader result) {
  const uint64_t leaseId = result.getLease();
  std::optional<DepositRegionGrant> region;
  if (auto granted = depositRegions_.find(leaseId); granted != depositRegions_.end()) {
    region = granted->second;
    depositRegions_.erase(granted);
  }
  auto lease = store_.lease(leaseId);
  // The worker's lease slot was freed, and refilled, as the Result arrived (runRound).
  // Results are idempotent: one for an unknown, closed or foreign lease is dropped.
  if (!lease || lease->worker != identity) {
    spdlog::info("dropped a result for lease {} (unknown, closed or not this worker's)", leaseId);
    return;
  }
  if (inRound_) roundResults_.push_back(leaseId);
  auto job = store_.job(lease->job);
  const bool active = job && isActive(job->state) && phaseOf(job->state) == lease->phase;
  JobContext* context = nullptr;
  if (active) context = &this->context(lease->job);
  try {
    sql::Transaction tx(store_.database());
    store_.completeLease(leaseId);
    if (active) {
      const auto sent = arrivedLeases_.find(leaseId);
      checkResultCounts(sent != arrivedLeases_.end() ? &sent->second.expected : nullptr, lease->phase, result);
      auto spec = context->reader();
      applyResult(store_,
                  {leaseId, lease->job, lease->phase, context->scene->cells().size(),
                   uint64_t(spec.getWidth()) * spec.getHeight()},
                  region ? &*region : nullptr, result);
      recordResultCounters(identity, *lease, result);
    }
    tx.commit();
  } catch (const BadResultError& e) {
    // Nothing of it was kept (the transaction rolled back): its lease is
    // traced again, by another worker where there is one.
    refuseResult(identity, *lease, e.what());
    return;
  } catch (const FilmRangeError& e) {
    // Beyond the film's range: a bad worker, or a scene far too bright,
    // which every worker would agree on (refuseResult).
    refuseResult(identity, *lease, e.what());
    return;
  } catch (const std::exception& e) {
    // A full disk is not the cell's fault: the round is undone and the
    // lease requeued (inRound).
    if (isDiskTrouble(e)) throw;
    // Nothing of it was kept (the transaction rolled back); its batches go
    // back to the queue, and a cell that keeps failing fails its job like
    // any failing cell.
    spdlog::error("rejected the result of lease {}: {}", leaseId, e.what());
    recordCellFailure(*lease, fmt::format("cell {}: {}", lease->cell, e.what()));
    return;
  }
  ++resultsApplied_;
  refusedResults_.erase({lease->job, lease->cell});
  takenBack_.erase({lease->job, lease->cell});
  retries_.erase({lease->job, lease->cell});
  if (active) advanceIfPhaseDone(lease->job);
}

void Coordinator::refuseResult(const std::string& identity, const LeaseRecord& lease, const std::string& reason) {
  const auto worker = workers_.find(identity);
  const std::string name = worker != workers_.end() ? worker->second.name : shortId(identity);
  ++refusalsByWorker_[name];
  std::vector<Refusal>& refusals = refusedResults_[{lease.job, lease.cell}];
  refusals.push_back({name, reason});
  {
    sql::Transaction tx(store_.database());
    store_.requeueLease(lease.id);
    store_.addCounter(lease.job, "results.refused", 1);
    tx.commit();
  }
  delayRetry(lease.job, lease.cell);
  spdlog::error("rejected the result of lease {} (job {} cell {}) from worker {}: {}; its work is traced again{}",
                lease.id, lease.job, lease.cell, name, reason,
                worker != workers_.end() && leftToOthers(worker->second, lease.job, lease.cell)
                    ? " by another worker"
                    : "");
  // Another worker's refused Result for the cell: they agree.
  for (const Refusal& earlier : refusals)
    if (earlier.worker != name) {
      failJob(lease.job, fmt::format("cell {}: {} (the Results of workers {} and {} alike: each was refused)",
                                     lease.cell, reason, earlier.worker, name));
      return;
    }
  if (int64_t(refusals.size()) >= options_.maxCellFailures)
    failJob(lease.job, fmt::format("cell {}: {} (the Result of worker {} refused {} times, with no other worker to "
                                   "trace it)",
                                   lease.cell, reason, name, refusals.size()));
}

bool Coordinator::leftToOthers(const WorkerInfo& worker, uint64_t job, uint32_t cell) const {
  const auto refused = refusedResults_.find({job, cell});
  if (refused == refusedResults_.end()) return false;
  const auto refusedFrom = [&](const std::string& name) {
    return std::any_of(refused->second.begin(), refused->second.end(),
                       [&](const Refusal& r) { return r.worker == name; });
  };
  if (!refusedFrom(worker.name)) return false;
  return std::any_of(workers_.begin(), workers_.end(), [&](const auto& other) {
    return other.second.ready && !refusedFrom(other.second.name) && !sidelined(other.second);
  });
}

bool Coordinator::sidelined(const WorkerInfo& worker) const {
  const auto count = [&](const WorkerInfo& w) {
    const auto found = refusalsByWorker_.find(w.name);
    return found == refusalsByWorker_.end() ? 0 : found->second;
  };
  if (count(worker) < kRefusalsBeforeSidelined) return false;
  return std::any_of(workers_.begin(), workers_.end(), [&](const auto& other) {
    return other.second.ready && count(other.second) < kRefusalsBeforeSidelined;
  });
}

uint64_t Coordinator::peakResident() {
  const int64_t now = nowMs();
  if (now - peakResidentReadMs_ >= 1000) {
    peakResident_ = peakResidentBytes();
    peakResidentReadMs_ = now;
  }
  return peakResident_;
}

// A Result's counters are summed into its job's, except the worker's peak
// memory, kept per worker as the largest it reported; the coordinator's own
// peak and the lease's line in the lease log go in the same transaction.
void Coordinator::recordResultCounters(const std::string& identity, const LeaseRecord& lease,
                                       wire::Result::Reader result) {
  const auto worker = workers_.find(identity);
  const std::string workerName = worker != workers_.end() ? worker->second.name : identity;
  LeaseLogEntry entry;
  for (auto counter : result.getCounters()) {
    const std::string_view name = counter.getName().cStr();
    if (name == kPeakResidentCounter) {
      store_.raiseCounter(lease.job, fmt::format("{}{}", kWorkerPeakResidentPrefix, workerName), counter.getValue());
      if (worker != workers_.end())
        worker->second.peakResidentBytes = std::max(worker->second.peakResidentBytes, counter.getValue());
      continue;
    }
    store_.addCounter(lease.job, name, counter.getValue());
    if (name == kLeaseTimeCounter) entry.leaseMicros = counter.getValue();
    else if (name == kLoadTimeCounter) entry.loadMicros = counter.getValue();
    else if (name == kLeaseCpuCounter) entry.cpuMicros = counter.getValue();
    else if (name == kLeaseRunQueueCounter) entry.runQueueMicros = counter.getValue();
    else if (name == kTrianglesLoadedCounter) entry.trianglesLoaded = counter.getValue();
    else if (name == "cells.loaded") entry.cellsLoaded = counter.getValue();
  }
  store_.addCounter(lease.job, "leases.completed", 1);
  if (worker != workers_.end() && worker->second.memoryBytes > 0)
    store_.raiseCounter(lease.job, fmt::format("{}{}", kWorkerMemoryBudgetPrefix, workerName),
                        int64_t(worker->second.memoryBytes));
  store_.raiseCounter(lease.job, kCoordinatorPeakResidentCounter, int64_t(peakResident()));
  store_.raiseCounter(lease.job, kCoordinatorCpuAtLastResultCounter, processCpuMicros());
  entry.job = lease.job;
  entry.lease = lease.id;
  entry.phase = lease.phase;
  entry.cell = lease.cell;
  entry.worker = workerName;
  entry.resultMs = wallMs();
  if (auto sent = arrivedLeases_.find(lease.id); sent != arrivedLeases_.end()) {
    entry.sentMs = sent->second.sentMs;
    entry.work = sent->second.work;
    entry.moreCells = uint32_t(sent->second.moreCellWork.size());
    entry.moreCellWork = std::move(sent->second.moreCellWork);
    entry.moreCellsLogged = true;
    arrivedLeases_.erase(sent);
  }
  store_.logLease(entry);
}

void Coordinator::onFailure(const std::string& identity, wire::Failure::Reader failure) {
  const uint64_t leaseId = failure.getLease();
  depositRegions_.erase(leaseId);
  auto lease = store_.lease(leaseId);
  if (auto worker = workers_.find(identity); worker != workers_.end()) {
    worker->second.leases.erase(leaseId);
  }
  if (!lease || lease->worker != identity) return;
  // The cell to blame: one of the lease's more cells, when the worker says so.
  const uint32_t cell = failure.getFailedCell() != kLeaseOwnCell ? failure.getFailedCell() : lease->cell;
  const std::string message = fmt::format("cell {}: {}", cell, failure.getMessage().cStr());
  spdlog::error("lease {} failed: {}", leaseId, message);
  recordCellFailure(*lease, message, cell);
}

void Coordinator::recordCellFailure(const LeaseRecord& lease, const std::string& message,
                                    std::optional<uint32_t> failedCell) {
  const uint32_t cell = failedCell.value_or(lease.cell);
  delayRetry(lease.job, cell);
  // A store the coordinator cannot read either (unmounted, moved away) is
  // not the cell's fault: the lease waits, uncounted, for it to come back.
  if (const auto unreadable = storeUnreadable(lease.job, cell)) {
    noteStoreTrouble(lease.job, *unreadable);
    {
      sql::Transaction tx(store_.database());
      store_.requeueLease(lease.id);
      tx.commit();
    }
    if (auto leftOut = storeLog_.admit(fmt::format("{}", lease.job)))
      spdlog::warn("job {}: lease {} failed ({}) while its store cannot be read ({}): requeued, not counted "
                   "against cell {}{}",
                   lease.job, lease.id, message, *unreadable, cell, leftOutSuffix(*leftOut));
    return;
  }
  // A cell that failed is not carried in other cells' leases again: its
  // retries are its own, and its failures do not fail innocent leases.
  failedCells_.insert({lease.job, cell});
  const std::string counter = fmt::format("failures.cell.{}", cell);
  int64_t failures;
  {
    sql::Transaction tx(store_.database());
    store_.requeueLease(lease.id);
    store_.addCounter(lease.job, counter, 1);
    failures = store_.counters(lease.job)[counter];
    tx.commit();
  }
  // A failure may be passing (a worker short of memory); one that repeats
  // (a corrupt cell file) would fail forever: give up after a few attempts.
  if (failures >= options_.maxCellFailures)
    failJob(lease.job, fmt::format("{} (failed {} times)", message, failures));
}

// 0.5 s after the first failure or loss, doubling to at most 30 s: three
// failures of a cell are never milliseconds apart, and a worker lost to
// something passing (a store remounted, memory short) finds it passed.
void Coordinator::delayRetry(uint64_t job, uint32_t cell) {
  Retry& retry = retries_[{job, cell}];
  retry.count = std::min(retry.count + 1, 16);
  retry.notBeforeMs = nowMs() + std::min<int64_t>(int64_t(500) << (retry.count - 1), 30000);
}

std::optional<std::string> Coordinator::storeUnreadable(uint64_t job, uint32_t cell) {
  std::string directory;
  try {
    const JobContext& ctx = context(job);
    directory = ctx.scene->directory();
    for (const std::string& path : {directory + "/scene.db", ctx.scene->cellPath(cell)})
      if (::access(path.c_str(), R_OK) != 0) return fmt::format("{}: {}", path, std::strerror(errno));
  } catch (const std::exception& e) {
    return std::string(e.what());
  }
  return std::nullopt;
}

std::optional<std::string> Coordinator::storeDirectoryOf(uint64_t jobId) {
  if (auto cached = jobs_.find(jobId); cached != jobs_.end()) return cached->second.scene->directory();
  auto job = store_.job(jobId);
  if (!job) return std::nullopt;
  net::PackedReader reader(job->spec.data(), job->spec.size());
  return std::string(reader.root<wire::JobSpec>().getStore().cStr());
}

void Coordinator::noteStoreTrouble(uint64_t job, const std::string& reason) {
  const auto [trouble, added] = storeTrouble_.try_emplace(job, StoreTrouble{wallMs(), reason});
  trouble->second.reason = reason;
  if (added)
    spdlog::warn("job {}: its store cannot be read ({}); the job waits for it, at most {} s (--store-gone-timeout)",
                 job, reason, options_.storeGoneTimeoutMs / 1000.0);
}

void Coordinator::checkStores() {
  for (const JobRecord& job : store_.jobs(true)) {
    std::optional<std::string> directory;
    try {
      directory = storeDirectoryOf(job.id);
    } catch (const std::exception&) {
    }
    if (!directory) continue;
    const std::string sceneDb = *directory + "/scene.db";
    if (::access(sceneDb.c_str(), R_OK) == 0) {
      if (storeTrouble_.erase(job.id)) spdlog::info("job {}: its store can be read again", job.id);
      continue;
    }
    noteStoreTrouble(job.id, fmt::format("{}: {}", sceneDb, std::strerror(errno)));
    const StoreTrouble& trouble = storeTrouble_.at(job.id);
    if (wallMs() - trouble.sinceMs >= options_.storeGoneTimeoutMs)
      failJob(job.id, fmt::format("store {} cannot be read since {} ({}): the job waited {} s for it "
                                  "(--store-gone-timeout)",
                                  *directory, utcTime(trouble.sinceMs), trouble.reason,
                                  options_.storeGoneTimeoutMs / 1000.0));
  }
}

std::vector<std::string> Coordinator::waitingReasons(const JobRecord& record) const {
  const uint64_t job = record.id;
  std::vector<std::string> reasons;
  if (diskRoundsUndone_ > 0) {
    const std::string directory =
        std::filesystem::absolute(options_.database).parent_path().lexically_normal().string();
    const bool full = diskTroubleWhat_.find("full") != std::string::npos ||
                      diskTroubleWhat_.find("No space") != std::string::npos;
    reasons.push_back(fmt::format("{} on {}: jobs.db or its files cannot be written since {} ({}); {} rounds "
                                  "undone, leasing resumes by itself once they can",
                                  full ? "disk full" : "disk trouble", directory, utcTime(diskTroubleSinceMs_),
                                  diskTroubleWhat_, diskRoundsUndone_));
  }
  if (auto trouble = storeTrouble_.find(job); trouble != storeTrouble_.end())
    reasons.push_back(fmt::format("store cannot be read since {} ({}); the job fails at {} unless it comes back "
                                  "(--store-gone-timeout)",
                                  utcTime(trouble->second.sinceMs), trouble->second.reason,
                                  utcTime(trouble->second.sinceMs + options_.storeGoneTimeoutMs)));
  for (auto it = takenBack_.lower_bound({job, 0}); it != takenBack_.end() && it->first.first == job; ++it)
    reasons.push_back(fmt::format("cell {}: its lease was taken back from worker {} at {}: {}; traced again by "
                                  "another worker",
                                  it->first.second, it->second.worker, utcTime(it->second.atMs), it->second.reason));
  for (auto it = refusedResults_.lower_bound({job, 0}); it != refusedResults_.end() && it->first.first == job; ++it)
    if (!it->second.empty())
      reasons.push_back(fmt::format("cell {}: the Result of worker {} was refused ({}); traced again",
                                    it->first.second, it->second.back().worker, it->second.back().reason));
  if (workers_.empty()) {
    reasons.push_back("no worker is connected");
  } else if (!record.requiredTags.empty()) {
    // Worker pools: a tag no connected worker has holds the job until one with it connects.
    for (const std::string& tag : record.requiredTags)
      if (std::none_of(workers_.begin(), workers_.end(), [&](const auto& w) { return hasAllTags(w.second.tags, {tag}); }))
        reasons.push_back(fmt::format("needs tag {}, no connected worker has it", tag));
    if (reasons.empty() && std::none_of(workers_.begin(), workers_.end(), [&](const auto& w) {
          return hasAllTags(w.second.tags, record.requiredTags);
        }))
      reasons.push_back(fmt::format("needs tags {}, no connected worker has them all", joinTags(record.requiredTags)));
  }
  return reasons;
}

// A job that ended (cancelled, failed) has its leases dropped; the workers
// tracing them stop between two batches instead of finishing work whose
// Results would be dropped, and their slots are free at once.
void Coordinator::recallLeasesOf(uint64_t job) {
  std::set<std::string> holders;
  for (const LeaseRecord& lease : store_.openLeases()) {
    if (lease.job != job) continue;
    holders.insert(lease.worker);
    if (auto worker = workers_.find(lease.worker); worker != workers_.end()) worker->second.leases.erase(lease.id);
  }
  for (const std::string& identity : holders) {
    capnp::MallocMessageBuilder message;
    message.initRoot<wire::Envelope>().initCancel().setJob(job);
    send(identity, message);
  }
}

void Coordinator::onFetchPhotons(const std::string& identity, wire::FetchPhotons::Reader request) {
  capnp::MallocMessageBuilder message;
  auto reply = message.initRoot<wire::Envelope>().initPhotons();
  reply.setJob(request.getJob());
  reply.setCell(request.getCell());
  // A reply with an error fails the worker's lease; it caches nothing.
  const auto refuse = [&](const std::string& error) {
    reply.setError(error);
    send(identity, message);
  };
  // Only a rendering job's photon tables are complete. A fetch for a lease
  // assigned before its job went back to the photon pass (or ended) must not
  // leave the worker caching a partial table.
  if (auto job = store_.job(request.getJob()); !job || job->state != JobState::Render) {
    refuse(fmt::format("job {} is not rendering: its photon tables are not final", request.getJob()));
    return;
  }
  if (!jobsLeasedTo(identity).count(request.getJob())) {
    refuse(fmt::format("job {}: this worker holds no lease of it", request.getJob()));
    return;
  }
  // A job that reuses an earlier job's photon pass reads that job's tables,
  // as long as that pass stands complete (a lender whose pass runs again
  // has none for now).
  const uint64_t job = request.getJob();
  const uint64_t photonJob = store_.job(job)->photonJob();
  if (photonJob != job) {
    if (auto lender = store_.job(photonJob); !lender || !lender->photonsComplete) {
      const std::string reason = fmt::format("the photon pass it reused (job {}) is no longer complete", photonJob);
      refuse(reason);
      restartPhotonPass(job, reason);
      return;
    }
  }
  // A worker that reads the photon file itself gets where the batches lie:
  // no photon bytes pass through this thread or its socket.
  if (request.getReadsPhotonFile())
    if (const auto extents = store_.photonExtents(photonJob, request.getCell())) {
      reply.setFile(std::filesystem::absolute(store_.photonFile(photonJob)).string());
      auto list = reply.initExtents(static_cast<unsigned>(extents->size()));
      for (size_t i = 0; i < extents->size(); ++i) {
        list[unsigned(i)].setOffset(uint64_t((*extents)[i].offset));
        list[unsigned(i)].setSize(uint64_t((*extents)[i].size));
        list[unsigned(i)].setCrc((*extents)[i].crc);
      }
      store_.addCounter(job, kPhotonTablesReadByWorkersCounter, 1);
      send(identity, message);
      return;
    }
  std::vector<std::string> blobs;
  try {
    blobs = store_.photonBatches(photonJob, request.getCell());
  } catch (const std::exception& e) {
    // A photon file damaged under a committed row (an operating-system crash
    // lost its pages, or someone wrote to it): the photons are gone, but the
    // pass that made them is deterministic. Run it again rather than fail
    // the job.
    refuse(e.what());
    if (photonJob != job) {
      withdrawDamagedLender(photonJob, e.what());
      restartPhotonPass(job, fmt::format("the photon tables of job {}, which it reused: {}", photonJob, e.what()));
    } else {
      restartPhotonPass(job, e.what());
    }
    return;
  }
  auto list = reply.initBatches(static_cast<unsigned>(blobs.size()));
  int64_t bytes = 0;
  for (size_t i = 0; i < blobs.size(); ++i) {
    list.set(static_cast<unsigned>(i),
             capnp::Data::Reader(reinterpret_cast<const kj::byte*>(blobs[i].data()), blobs[i].size()));
    bytes += int64_t(blobs[i].size());
  }
  if (bytes > 0) store_.addCounter(job, kPhotonBytesSentCounter, bytes);
  send(identity, message, net::Encoding::Flat);   // photon records: bytes, not words to squeeze
}

std::set<uint64_t> Coordinator::jobsLeasedTo(const std::string& identity) {
  std::set<uint64_t> jobs;
  auto worker = workers_.find(identity);
  if (worker == workers_.end()) return jobs;
  for (const auto& [lease, inFlight] : worker->second.leases)
    if (auto record = store_.lease(lease); record && record->worker == identity) jobs.insert(record->job);
  return jobs;
}

void Coordinator::onFetchFile(const std::string& identity, wire::FetchFile::Reader request) {
  // Only the stores of the active jobs this worker holds leases of: a
  // finished or failed job's store is no longer served.
  std::set<std::string> stores;
  for (uint64_t job : jobsLeasedTo(identity))
    if (auto record = store_.job(job); record && isActive(record->state)) stores.insert(context(job).scene->directory());
  capnp::MallocMessageBuilder message;
  auto chunk = message.initRoot<wire::Envelope>().initFileChunk();
  serveFileChunk(stores, request, chunk);
  if (chunk.hasError() && chunk.getError().size())
    spdlog::warn("refused a file to {}: {}", shortId(identity), chunk.getError().cStr());
  send(identity, message);
}

void Coordinator::onFetchImage(const std::string& identity, const std::optional<net::Peer>& peer,
                               wire::FetchImage::Reader request) {
  capnp::MallocMessageBuilder message;
  auto reply = message.initRoot<wire::Envelope>().initImage();
  reply.setJob(request.getJob());
  try {
    auto job = store_.job(request.getJob());
    if (!job) throw std::runtime_error(fmt::format("job {} does not exist", request.getJob()));
    if (!mayManage(peer, *job)) throw std::runtime_error(notYours(*job, "fetch its image"));
    if (job->state != JobState::Done)
      throw std::runtime_error(fmt::format("job {} is {}, not done: it has no image", job->id, toString(job->state)));
    auto spec = context(job->id).reader();
    reply.setOutput(spec.getOutput());
    const std::string image = encodeJobImage(store_, *job, spec, *context(job->id).scene);
    reply.setImage(capnp::Data::Reader(reinterpret_cast<const kj::byte*>(image.data()), image.size()));
    reply.setStatistics(jobStatistics(store_, *job, spec).dump(2) + "\n");
  } catch (const std::exception& e) {
    reply.setError(e.what());
  }
  send(identity, message);
}

void Coordinator::onSubmit(const std::string& identity, const std::optional<net::Peer>& peer,
                           wire::Submit::Reader submit) {
  capnp::MallocMessageBuilder reply;
  auto answer = reply.initRoot<wire::Envelope>().initSubmitReply();
  try {
    JobSettings settings = jobSettingsFromWire(submit.getSpec());
    // A relative path would be read against the coordinator's working
    // directory, not the client's: clients resolve them (fillSubmit).
    for (const auto& [what, path] : {std::pair<const char*, const std::string&>{"scene store", settings.store},
                                     {"output", settings.output}})
      if (!std::filesystem::path(path).is_absolute())
        throw std::invalid_argument(fmt::format("{} '{}' is a relative path: a Submit names absolute paths (the "
                                                "coordinator's working directory is not the client's)",
                                                what, path));
    // The store as the coordinator resolves it, once: what it serves and
    // workers read is that directory, whatever its path's links become.
    std::error_code unresolved;
    const auto store = std::filesystem::canonical(settings.store, unresolved);
    if (unresolved) throw std::runtime_error(fmt::format("scene store {}: {}", settings.store, unresolved.message()));
    settings.store = store.string();
    checkOutputPath(settings.output, settings.analysis ? OutputKind::AnalysisCsv : OutputKind::Image);
    auto scene = std::make_unique<SceneStore>(SceneStore::open(settings.store));
    requireRegularStoreFiles(*scene);
    settings = resolveJobSettings(std::move(settings), *scene);
    validateJobSettings(settings, *scene);
    // An analysis's sensors, checked and located in their cells.
    std::vector<Sensor> sensors;
    if (settings.analysis) {
      if (submit.getSensors().size() != settings.analysis->sensors)
        throw std::invalid_argument(fmt::format("the analysis names {} sensors, the submit carries {}",
                                                settings.analysis->sensors, submit.getSensors().size()));
      sensors = sensorsOfSubmit(submit.getSensors(), *scene);
    } else if (submit.getSensors().size() > 0) {
      throw std::invalid_argument("sensors in a submit that is no analysis");
    }
    const int priority = checkedPriority(submit.getPriority());
    std::vector<std::string> requiredTags;
    for (const auto tag : submit.getRequiredTags()) requiredTags.emplace_back(tag.cStr());
    requiredTags = normalizedTags(std::move(requiredTags), "required tags");
    auto spec = std::make_unique<capnp::MallocMessageBuilder>();
    toWire(settings, spec->initRoot<wire::JobSpec>());
    auto builder = spec->getRoot<wire::JobSpec>();
    const std::string packed = net::packToString(*spec);
    // An earlier job's finished photon pass on the same store with the same
    // photon settings gives the same tables, bit for bit: reused unless the
    // submit asks for a pass of its own.
    const std::string photonKey = photonPassKey(settings, *scene);
    const std::optional<uint64_t> lender =
        submit.getFreshPhotons() ? std::nullopt : store_.reusablePhotonPass(photonKey);
    uint64_t job;
    {
      const int64_t cpuAtSubmit = processCpuMicros();
      sql::Transaction tx(store_.database());
      job = store_.createJob(packed, wallMs());
      store_.addCounter(job, kCoordinatorCpuAtSubmitCounter, cpuAtSubmit);
      store_.setPhotonPass(job, photonKey, lender.value_or(0));
      store_.setPriority(job, priority);
      store_.setRequiredTags(job, requiredTags);
      store_.setOwner(job, peer ? peer->who : std::string());
      if (settings.analysis) {
        store_.setJobSensors(job, encodeSensors(sensors));
        const auto outside = std::count_if(sensors.begin(), sensors.end(), [](const Sensor& s) { return s.cell < 0; });
        if (outside > 0)
          spdlog::warn("job {}: {} of its {} sensors lie outside every cell: not measured, their rows left empty",
                       job, outside, sensors.size());
      }
      if (!lender) queuePhotonEmission(store_, job, builder.asReader(), *scene, &stopping_);
      tx.commit();
    }
    JobContext context{std::move(spec), std::move(scene), lender.value_or(job)};
    jobs_.emplace(job, std::move(context));
    // A job with nothing to emit (a cell or portal picture, or one reusing
    // a photon pass) goes straight to rendering.
    advanceIfPhaseDone(job);
    answer.setJob(job);
    spdlog::info("job {} submitted: {} photons{}, {} spp, {}x{}, scene {}, priority {}{}{}", job, builder.getPhotons(),
                 lender ? fmt::format(" (the photon pass of job {}, reused)", *lender) : "", builder.getSpp(),
                 builder.getWidth(), builder.getHeight(), builder.getStore().cStr(), priority,
                 requiredTags.empty() ? "" : ", requires tags ", joinTags(requiredTags));
  } catch (const std::exception& e) {
    answer.setError(e.what());
    spdlog::warn("submit refused: {}", e.what());
  }
  send(identity, reply);
}

void Coordinator::onStatus(const std::string& identity, const std::optional<net::Peer>& peer,
                           wire::StatusRequest::Reader request) {
  replyStatus(identity, peer, request.getJob());
}

bool Coordinator::mayManage(const std::optional<net::Peer>& peer, const JobRecord& job) const {
  if (!security_->ownersApart()) return true;   // one user's own keys or uid: every peer is that user
  if (!peer) return false;
  return peer->role == net::Role::Operator || (!job.owner.empty() && job.owner == peer->who);
}

std::string Coordinator::notYours(const JobRecord& job, const std::string& action) {
  return fmt::format("job {} is another user's: only its owner or an operator may {}", job.id, action);
}

void Coordinator::replyStatus(const std::string& identity, const std::optional<net::Peer>& peer, uint64_t jobId) {
  nlohmann::json status;
  const int64_t now = wallMs();
  if (jobId != 0) {
    auto job = store_.job(jobId);
    if (!job) {
      sendError(identity, fmt::format("job {} does not exist", jobId));
      return;
    }
    // A job whose store cannot be loaded still has a status: its spec as stored.
    std::optional<net::PackedReader> stored;
    wire::JobSpec::Reader spec;
    try {
      spec = context(job->id).reader();
    } catch (const std::exception&) {
      spec = stored.emplace(job->spec.data(), job->spec.size()).root<wire::JobSpec>();
    }
    status = jobStatus(store_, *job, spec, now);
    if (isActive(job->state))
      if (const auto reasons = waitingReasons(*job); !reasons.empty()) {
        status["waiting"] = reasons;
        status.erase("eta_s");   // it would only grow
      }
    const bool mine = mayManage(peer, *job);
    status["mine"] = mine;
    if (!mine) hideOwnersDetail(status);
  } else {
    status["jobs"] = nlohmann::json::array();
    for (const JobRecord& job : store_.jobs(false)) {
      const bool mine = mayManage(peer, job);
      nlohmann::json listed = {{"job", job.id},
                               {"state", std::string(toString(job.state))},
                               {"error", job.error},
                               {"priority", job.priority},
                               {"required_tags", job.requiredTags},
                               {"mine", mine}};
      if (!mine) hideOwnersDetail(listed);
      status["jobs"].push_back(std::move(listed));
    }
  }
  // Since it started, all jobs: its CPU (every thread) over the leases it
  // sent or the Results it applied is its cost per lease.
  status["coordinator"] = {{"cpu_us", processCpuMicros()},
                           {"leases_sent", leasesSent_},
                           {"results_applied", resultsApplied_}};
  status["workers"] = workersStatus(workers_, nowMs());
  for (auto& worker : status["workers"]) {
    const auto refused = refusalsByWorker_.find(worker.value("name", ""));
    worker["refused_results"] = refused == refusalsByWorker_.end() ? 0 : refused->second;
  }
  capnp::MallocMessageBuilder message;
  message.initRoot<wire::Envelope>().initStatusReply().setJson(status.dump());
  send(identity, message);
}

void Coordinator::onCancel(const std::string& identity, const std::optional<net::Peer>& peer,
                           wire::CancelRequest::Reader request) {
  auto job = store_.job(request.getJob());
  if (!job) {
    sendError(identity, fmt::format("job {} does not exist", request.getJob()));
    return;
  }
  if (!mayManage(peer, *job)) {
    spdlog::warn("refused to cancel job {} for {}: not its owner", job->id, shortId(identity));
    sendError(identity, notYours(*job, "cancel it"));
    return;
  }
  if (isActive(job->state)) {
    recallLeasesOf(job->id);
    sql::Transaction tx(store_.database());
    store_.dropJobWork(job->id);
    store_.setJobState(job->id, JobState::Cancelled, wallMs(), "cancelled by the user");
    tx.commit();
    forgetEndedJob(job->id);
    spdlog::info("job {} cancelled", job->id);
  }
  replyStatus(identity, peer, job->id);
}

void Coordinator::onJobDetail(const std::string& identity, const std::optional<net::Peer>& peer,
                              wire::JobDetailRequest::Reader request) {
  const auto job = store_.job(request.getJob());
  if (!job) {
    sendError(identity, fmt::format("job {} does not exist", request.getJob()));
    return;
  }
  nlohmann::json detail = cellActivity(store_, *job, workers_);
  // Its log names its files: its owner's (and operators') only.
  detail["log"] = options_.jobLog && mayManage(peer, *job) ? options_.jobLog->lines(job->id) : std::vector<std::string>();
  capnp::MallocMessageBuilder message;
  message.initRoot<wire::Envelope>().initJobDetailReply().setJson(detail.dump());
  send(identity, message);
}

void Coordinator::onFetchPreview(const std::string& identity, const std::optional<net::Peer>& peer,
                                 wire::FetchPreview::Reader request) {
  capnp::MallocMessageBuilder message;
  auto reply = message.initRoot<wire::Envelope>().initPreview();
  reply.setJob(request.getJob());
  try {
    const auto job = store_.job(request.getJob());
    if (!job) throw std::runtime_error(fmt::format("job {} does not exist", request.getJob()));
    if (!mayManage(peer, *job)) throw std::runtime_error(notYours(*job, "see its image"));
    // The spec as stored (resolved at submit): no need to open the store.
    net::PackedReader stored(job->spec.data(), job->spec.size());
    const auto spec = stored.root<wire::JobSpec>();
    if (spec.hasAnalysis()) throw std::runtime_error(fmt::format("job {} is a lighting analysis: no image", job->id));
    const int64_t cameraRays = store_.counters(job->id)["rays.camera"];
    if (job->state == JobState::Photons || cameraRays == 0)
      throw std::runtime_error(fmt::format("job {} has rendered nothing yet", job->id));
    const LinearImage preview = shrinkImage(filmImage(store_, *job, spec), request.getMaxSide());
    reply.setWidth(preview.width);
    reply.setHeight(preview.height);
    static_assert(std::endian::native == std::endian::little, "PreviewReply.rgb is little-endian float32");
    reply.setRgb(capnp::Data::Reader(reinterpret_cast<const kj::byte*>(preview.rgb.data()),
                                     preview.rgb.size() * sizeof(float)));
    reply.setExposure(spec.getExposure());
    reply.setCameraRaysDone(cameraRays);
  } catch (const std::exception& e) {
    reply.setError(e.what());
  }
  send(identity, message);
}

void Coordinator::onPriority(const std::string& identity, const std::optional<net::Peer>& peer,
                             wire::PriorityRequest::Reader request) {
  auto job = store_.job(request.getJob());
  if (!job) {
    sendError(identity, fmt::format("job {} does not exist", request.getJob()));
    return;
  }
  if (!mayManage(peer, *job)) {
    sendError(identity, notYours(*job, "change its priority"));
    return;
  }
  int priority;
  try {
    priority = checkedPriority(request.getPriority());
  } catch (const std::invalid_argument& e) {
    sendError(identity, e.what());
    return;
  }
  if (!isActive(job->state)) {
    sendError(identity, fmt::format("job {} is {}: its priority no longer matters", job->id, toString(job->state)));
    return;
  }
  // The scheduler reads it at each lease (JobStore::pendingCells): the
  // leases in flight finish, the next ones follow the new order.
  {
    sql::Transaction tx(store_.database());
    store_.setPriority(job->id, priority);
    tx.commit();
  }
  spdlog::info("job {}: priority {} (was {})", job->id, priority, job->priority);
  replyStatus(identity, peer, job->id);
}

void Coordinator::onGoodbye(const std::string& identity) { releaseWorker(identity, "left"); }

void Coordinator::releaseWorker(const std::string& identity, const std::string& reason) {
  auto it = workers_.find(identity);
  if (it == workers_.end()) return;
  for (const LeaseRecord& lease : store_.openLeasesOf(identity)) {
    {
      sql::Transaction tx(store_.database());
      store_.requeueLease(lease.id, true);
      store_.addCounter(lease.job, "leases.lost", 1);
      tx.commit();
    }
    depositRegions_.erase(lease.id);   // its Result, if one still comes, is dropped
    spdlog::warn("lease {} (job {} cell {}, attempt {}) requeued: worker {} {}", lease.id, lease.job, lease.cell,
                 lease.attempt, it->second.name, reason);
    // Workers die of other things than their cell (a kill from outside,
    // the OOM killer, a node taken back), which a lost lease cannot tell
    // apart: the cell waits a while, longer each time, and only a cell
    // lost --max-lost-leases times is taken for what kills its workers (a
    // crash in its geometry, memory it exhausts) and fails its job.
    delayRetry(lease.job, lease.cell);
    if (lease.attempt >= uint32_t(options_.maxLostLeases))
      failJob(lease.job, fmt::format("cell {}: its lease was lost {} times, each time with its worker (last: {} {}); "
                                     "a cell that kills its workers? (--max-lost-leases)",
                                     lease.cell, lease.attempt, it->second.name, reason));
  }
  spdlog::info("worker {} {}", it->second.name, reason);
  workers_.erase(it);
}

void Coordinator::noteProgress(WorkerInfo& worker) {
  worker.progressMs = nowMs();
  if (worker.stalledSinceMs == 0) return;
  spdlog::info("worker {} moves again, {:.1f} s after its leases were taken back; it takes leases again", worker.name,
               (worker.progressMs - worker.stalledSinceMs) / 1000.0);
  worker.stalledSinceMs = 0;
  worker.stallReason.clear();
}

void Coordinator::checkLeaseProgress() {
  const int64_t now = nowMs();
  for (auto& [identity, worker] : workers_)
    if (!worker.leases.empty() && now - worker.progressMs > options_.leaseTimeoutMs)
      takeBackLeases(worker, now - worker.progressMs);
}

// Its heartbeats say it is alive, yet nothing of its leases moved for
// leaseTimeoutMs: its tracing thread is stuck (a read that never returns:
// a hung file system, a FIFO) or its work is lost. Its leases go back to
// the queue, for other workers to trace with the same bits; the one it was
// tracing counts against its cell as a reported failure does (a cell that
// hangs every worker fails its job after --max-cell-failures), those
// queued behind it against nothing; a Result that still comes for any of
// them is dropped (the lease is gone, and with it its deposit region); and
// the worker gets no lease until it moves again (noteProgress).
void Coordinator::takeBackLeases(WorkerInfo& worker, int64_t stillMs) {
  const std::string why = fmt::format("no progress for {:.1f} s (--lease-timeout-s {:g})", stillMs / 1000.0,
                                      options_.leaseTimeoutMs / 1000.0);
  worker.stalledSinceMs = nowMs();
  worker.stallReason = fmt::format("{}, since {}", why, utcTime(wallMs() - stillMs));
  worker.leases.clear();
  for (const LeaseRecord& lease : store_.openLeasesOf(worker.identity)) {
    if (!store_.lease(lease.id)) continue;   // its job failed as an earlier one was taken back
    depositRegions_.erase(lease.id);
    takenBack_[{lease.job, lease.cell}] = {worker.name, why, wallMs()};
    const bool tracing = lease.id == worker.tracingLease;
    spdlog::error("lease {} (job {} cell {}) taken back from worker {}: {}{}; its work is traced again", lease.id,
                  lease.job, lease.cell, worker.name, why, tracing ? ", stuck tracing it" : ", queued there");
    {
      sql::Transaction tx(store_.database());
      store_.addCounter(lease.job, "leases.taken_back", 1);
      if (!tracing) store_.requeueLease(lease.id);
      tx.commit();
    }
    if (tracing)
      recordCellFailure(lease, fmt::format("cell {}: its lease was taken back from worker {}: {}", lease.cell,
                                           worker.name, why));
  }
}

void Coordinator::checkLiveness() {
  const int64_t now = nowMs();
  std::vector<std::string> dead;
  for (const auto& [identity, worker] : workers_)
    if (now - worker.lastSeenMs > options_.livenessMs) dead.push_back(identity);
  for (const std::string& identity : dead) releaseWorker(identity, "presumed dead (no heartbeat)");
}

void Coordinator::advanceIfPhaseDone(uint64_t jobId) {
  auto job = store_.job(jobId);
  if (!job || !isActive(job->state)) return;
  const int phase = phaseOf(job->state);
  if (store_.hasRemainingWork(jobId, phase) || store_.openLeaseCount(jobId) > 0) return;
  const int64_t now = wallMs();
  JobContext* ctx;
  try {
    ctx = &context(jobId);
  } catch (const std::exception& e) {
    failJob(jobId, e.what());
    return;
  }
  if (job->state == JobState::Photons) {
    sql::Transaction tx(store_.database());
    store_.addCounter(jobId, "time.photons_ms", now - job->phaseStartedMs);
    queueCameraRays(store_, jobId, ctx->reader(), *ctx->scene);
    if (!job->photonSource) store_.markPhotonPassComplete(jobId);
    store_.setJobState(jobId, JobState::Render, now);
    tx.commit();
    ctx->renderPass = 0;   // also after a photon pass run again mid-render
    spdlog::info("job {}: photon phase done, rendering", jobId);
  } else if (!startNextRenderPass(*job, *ctx, now)) {
    finishJob(jobId);
  }
}

bool Coordinator::startNextRenderPass(const JobRecord& job, JobContext& ctx, int64_t now) {
  PassEnd end;
  {
    sql::Transaction tx(store_.database());
    end = endRenderPass(store_, job, ctx.reader(), now);
    if (end.stop == PassStop::None)
      queueCameraRays(store_, job.id, ctx.reader(), *ctx.scene);
    else if (!end.recordedBefore)
      store_.addCounter(job.id, "time.render_ms", now - job.phaseStartedMs);
    tx.commit();
  }
  if (ctx.reader().getMaxPasses() > 1)
    spdlog::info("job {}: render pass {} done, error estimate {}{}", job.id, end.pass,
                 end.errorEstimate ? fmt::format("{:.3f} %", 100 * *end.errorEstimate) : "none yet",
                 end.stop == PassStop::None ? ", next pass" : fmt::format(", stopping: {}", toString(end.stop)));
  if (end.stop != PassStop::None) return false;
  ctx.renderPass = end.pass;   // the next pass's index: passes count from 1, indices from 0
  // The average of the passes so far, for whoever watches the file; the
  // job goes on whether or not it can be written.
  try {
    writeJobOutputs(store_, job, ctx.reader(), *ctx.scene);
  } catch (const std::exception& e) {
    spdlog::warn("job {}: the image after render pass {} could not be written: {}", job.id, end.pass, e.what());
  }
  return true;
}

void Coordinator::finishJob(uint64_t jobId) {
  auto job = store_.job(jobId);
  JobContext& ctx = context(jobId);
  job->state = JobState::Done;
  job->finishedMs = wallMs();
  // An image that cannot be written (its directory gone or read-only, no
  // descriptor left) loses nothing: the job is done, its film stays, and
  // `portico fetch-image` writes it where its client can.
  std::string outputError;
  try {
    writeJobOutputs(store_, *job, ctx.reader(), *ctx.scene);
  } catch (const std::exception& e) {
    outputError = fmt::format("the image could not be written ({}); `portico fetch-image {} -o FILE` writes it",
                              e.what(), jobId);
  }
  sql::Transaction tx(store_.database());
  store_.setJobState(jobId, JobState::Done, job->finishedMs, outputError);
  tx.commit();
  forgetEndedJob(jobId);
  if (outputError.empty())
    spdlog::info("job {} done: {}", jobId, ctx.reader().getOutput().cStr());
  else
    spdlog::error("job {} done, but {}", jobId, outputError);
}

void Coordinator::restartPhotonPass(uint64_t jobId, const std::string& reason) {
  auto job = store_.job(jobId);
  if (!job || !isActive(job->state)) return;
  // A disk that keeps damaging the file would otherwise loop for ever.
  const auto counters = store_.counters(jobId);
  const auto restarts = counters.find(JobStore::kPhotonPassRestarts);
  if (restarts != counters.end() && restarts->second >= options_.maxCellFailures) {
    failJob(jobId, fmt::format("{} (its photon pass was run again {} times)", reason, restarts->second));
    return;
  }
  try {
    JobContext& context = this->context(jobId);
    sql::Transaction tx(store_.database());
    store_.restartJob(jobId, wallMs());
    queuePhotonEmission(store_, jobId, context.reader(), *context.scene);
    tx.commit();
    context.photonJob = jobId;
  } catch (const std::exception& e) {
    failJob(jobId, fmt::format("{}; running its photon pass again failed: {}", reason, e.what()));
    return;
  }
  spdlog::error("job {}: {}; running its photon pass again", jobId, reason);
}

void Coordinator::withdrawDamagedLender(uint64_t lender, const std::string& reason) {
  if (auto job = store_.job(lender); job && isActive(job->state)) {
    restartPhotonPass(lender, reason);
    return;
  }
  sql::Transaction tx(store_.database());
  store_.withdrawPhotonPass(lender);
  tx.commit();
  spdlog::error("job {}: {}; its photon pass is not reused again", lender, reason);
}

void Coordinator::forgetEndedJob(uint64_t jobId) {
  storeTrouble_.erase(jobId);
  std::erase_if(takenBack_, [&](const auto& entry) { return entry.first.first == jobId; });
  std::erase_if(refusedResults_, [&](const auto& entry) { return entry.first.first == jobId; });
}

void Coordinator::failJob(uint64_t jobId, const std::string& error) {
  // The first reason stands: a job fails once.
  if (auto job = store_.job(jobId); !job || !isActive(job->state)) return;
  recallLeasesOf(jobId);
  sql::Transaction tx(store_.database());
  store_.dropJobWork(jobId);
  store_.setJobState(jobId, JobState::Failed, wallMs(), error);
  tx.commit();
  spdlog::error("job {} failed: {}", jobId, error);
  forgetEndedJob(jobId);
}

}  // namespace portico
