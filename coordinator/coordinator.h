// The coordinator service: owns jobs.db, talks to workers and clients over
// one ZeroMQ ROUTER socket, and schedules cell leases.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <set>
#include <optional>
#include <random>
#include <unordered_map>
#include <utility>
#include <vector>
#include <zmq.hpp>

#include "common/net/message.h"
#include "common/net/role.h"
#include "common/util/log_throttle.h"
#include "common/scene/store/scene_store.h"
#include "coordinator/deposit_regions.h"
#include "coordinator/job_log.h"
#include "coordinator/job_store.h"
#include "coordinator/router_security.h"
#include "coordinator/worker_registry.h"

namespace portico {

struct CoordinatorOptions {
  std::string listen = "tcp://127.0.0.1:5555";
  std::string database = "jobs.db";
  std::string endpointFile;        // where to write the bound endpoint (for port 0 / '*')
  int heartbeatMs = 1000;
  int livenessMs = 10000;          // silence after which a worker is presumed dead
  int64_t maxLeaseWork = 50000;    // most rays per lease; each worker's leases are sized to ~1 s of its measured speed
  int64_t maxCellFailures = 3;     // failures workers report for one cell before its job fails
  // Leases of one cell lost with their worker (killed from outside, out of
  // memory, a node gone: nothing reported) before its job fails. Healthy
  // workers are lost too, so it is higher than maxCellFailures.
  int64_t maxLostLeases = 10;
  std::string keysDirectory;       // CURVE keys (`portico keys generate`); required beyond loopback
  // Fault injection for recovery tests: every Nth transaction of the main
  // loop (Coordinator::inRound) that applies Results fails to commit (0: never).
  int64_t failCommitsEvery = 0;
  // Photon leases come with a deposit region of the job's photon file, which
  // workers that can open it write their deposits into themselves
  // (coordinator/deposit_regions.h); false: every deposit comes in its Result.
  bool depositRegions = true;
  // A job whose scene store the coordinator cannot read (deleted, moved,
  // unmounted) waits this long for it to come back, then fails saying so.
  int64_t storeGoneTimeoutMs = 600000;
  // A worker that holds leases and shows no progress for this long (no
  // Result, Failure or fetch, and heartbeats whose progress did not move)
  // has them taken back and traced elsewhere: its tracing is stuck (a read
  // that never returns) though its heartbeats go on.
  int64_t leaseTimeoutMs = 120000;
  // The recent log lines of each job, for JobDetail (the dashboard); null:
  // none kept. portico-coordinator adds it to spdlog's sinks.
  std::shared_ptr<JobLog> jobLog;
};

class Coordinator {
 public:
  explicit Coordinator(CoordinatorOptions options);
  ~Coordinator();
  // Serves until stop() or a Shutdown request.
  void run();
  void stop() { stopping_ = true; }
  const std::string& endpoint() const { return endpoint_; }

 private:
  struct JobContext {
    std::unique_ptr<capnp::MallocMessageBuilder> spec;   // root: wire::JobSpec
    std::unique_ptr<SceneStore> scene;
    uint64_t photonJob = 0;   // whose photon tables its render leases read (JobRecord::photonJob)
    uint32_t renderPass = 0;   // the render pass being rendered (0: the first), whose seed render leases carry
    wire::JobSpec::Reader reader() { return spec->getRoot<wire::JobSpec>().asReader(); }
  };

  void handle(const std::string& identity, const net::Decoded& message, size_t bytes,
              const std::optional<net::Peer>& peer);
  static std::optional<net::Role> roleOf(const std::optional<net::Peer>& peer) {
    return peer ? std::optional<net::Role>(peer->role) : std::nullopt;
  }
  // Whether `peer` may see `job` in full (its paths, error, log, image) and
  // steer it (cancel, priority): with per-user keys (RouterSecurity::
  // ownersApart) its owner and operators only; else every peer, all being
  // this user. A job without an owner (schema 13 and before) is operators'.
  bool mayManage(const std::optional<net::Peer>& peer, const JobRecord& job) const;
  static std::string notYours(const JobRecord& job, const std::string& action);
  void onHello(const std::string& identity, wire::Hello::Reader hello);
  void onReady(const std::string& identity);
  void onResult(const std::string& identity, wire::Result::Reader result);
  void recordResultCounters(const std::string& identity, const LeaseRecord& lease, wire::Result::Reader result);
  // A Result that does not add up or holds impossible values (result_check.h):
  // dropped, its lease traced again by another worker where one is ready,
  // counted against its worker. The job fails only when the Results of two
  // workers for the cell were refused (they agree: the cell's doing, such
  // as a scene too bright for the film), or, with no other worker to try,
  // maxCellFailures of one worker's.
  void refuseResult(const std::string& identity, const LeaseRecord& lease, const std::string& reason);
  // A cell one of whose Results from this worker was refused, while a ready
  // worker whose Result for it was not exists: left to the others.
  bool leftToOthers(const WorkerInfo& worker, uint64_t job, uint32_t cell) const;
  // A worker with kRefusalsBeforeSidelined refused Results gets no lease
  // while a ready worker with fewer exists.
  bool sidelined(const WorkerInfo& worker) const;
  void onFailure(const std::string& identity, wire::Failure::Reader failure);
  void onFetchPhotons(const std::string& identity, wire::FetchPhotons::Reader request);
  // The job back to the start of its photon pass, one of its own (its
  // photons, or those of the job it reused, unreadable).
  void restartPhotonPass(uint64_t job, const std::string& reason);
  // A reusing job's lender's photon tables were found damaged: the lender
  // runs its pass again if it still runs, else it lends no more.
  void withdrawDamagedLender(uint64_t lender, const std::string& reason);
  void onFetchFile(const std::string& identity, wire::FetchFile::Reader request);
  void onFetchImage(const std::string& identity, const std::optional<net::Peer>& peer, wire::FetchImage::Reader request);
  // The jobs of the leases the worker holds (what it may fetch files and photons of).
  std::set<uint64_t> jobsLeasedTo(const std::string& identity);
  void onSubmit(const std::string& identity, const std::optional<net::Peer>& peer, wire::Submit::Reader submit);
  void onStatus(const std::string& identity, const std::optional<net::Peer>& peer, wire::StatusRequest::Reader request);
  // job 0: all jobs; other users' without their paths, errors and logs (mayManage).
  void replyStatus(const std::string& identity, const std::optional<net::Peer>& peer, uint64_t job);
  void onCancel(const std::string& identity, const std::optional<net::Peer>& peer, wire::CancelRequest::Reader request);
  // The dashboard's (coordinator/job_activity.h): a job's cells and log
  // lines, and its film so far, made small.
  void onJobDetail(const std::string& identity, const std::optional<net::Peer>& peer,
                   wire::JobDetailRequest::Reader request);
  void onFetchPreview(const std::string& identity, const std::optional<net::Peer>& peer,
                      wire::FetchPreview::Reader request);
  // A job's new priority, for its leases from now on (those in flight finish).
  void onPriority(const std::string& identity, const std::optional<net::Peer>& peer, wire::PriorityRequest::Reader request);
  void onGoodbye(const std::string& identity);

  void dispatch();
  // Whether a worker wants a lease while work is pending (dispatch has
  // something to try).
  bool leaseWanted();
  // One lease for the worker; or none, because no work is pending at all
  // (dispatch stops) or because what is pending is best left to the
  // workers that hold its cells (the next worker is asked).
  enum class Assignment { Assigned, NothingForThisWorker, NothingLeft };
  Assignment assignWork(WorkerInfo& worker);
  // Requeues a failed lease; fails the job once its cell has failed too often.
  // `failedCell`: which of the lease's cells failed (default: its own).
  void recordCellFailure(const LeaseRecord& lease, const std::string& message,
                         std::optional<uint32_t> failedCell = std::nullopt);
  // A failed or lost lease's cell waits before it is leased again, longer
  // each time (retryDelayMs); a Result of the cell clears it.
  void delayRetry(uint64_t job, uint32_t cell);
  // Whether the coordinator can read the job's store itself: when it
  // cannot, a failure to read it is the store's (unmounted, moved), not the cell's.
  std::optional<std::string> storeUnreadable(uint64_t job, uint32_t cell);
  // Each heartbeat: whether each active job's store can be read; a job
  // whose store stayed unreadable for storeGoneTimeoutMs fails.
  void checkStores();
  void noteStoreTrouble(uint64_t job, const std::string& reason);
  // The job's store directory, from its loaded context or its stored spec.
  std::optional<std::string> storeDirectoryOf(uint64_t job);
  // What the coordinator keeps in memory about an active job, dropped as it ends.
  void forgetEndedJob(uint64_t job);
  // Why an active job makes no progress, as its status says it: the disk,
  // its store, refused Results, no workers. Empty: nothing known holds it.
  // A job requiring a tag no connected worker has says so.
  std::vector<std::string> waitingReasons(const JobRecord& job) const;
  // The workers tracing leases of a job that ended stop them (Cancel).
  void recallLeasesOf(uint64_t job);
  // A transaction failed for want of disk (full, failing): leasing pauses,
  // with back-off, and the log says so once in a while, not every round.
  static bool isDiskTrouble(const std::exception& e);
  void noteDiskTrouble(const std::string& what);
  // Leases jobs.db holds open that no worker is tracing go back to the queue.
  void requeueUntracedLeases();
  void advanceIfPhaseDone(uint64_t job);
  // The render phase ran out of work: the pass ends (render_passes.h);
  // true when another pass was queued.
  bool startNextRenderPass(const JobRecord& job, JobContext& context, int64_t nowMs);
  void finishJob(uint64_t job);
  void failJob(uint64_t job, const std::string& error);
  void checkLiveness();
  // A sign that the worker's leases move (a Result, a Failure, a fetch, a
  // heartbeat whose progress grew): its lease clock starts again, and a
  // worker taken for stuck takes leases again.
  void noteProgress(WorkerInfo& worker);
  // Each heartbeat: the leases of a worker with none of those signs for
  // leaseTimeoutMs are taken back (takeBackLeases).
  void checkLeaseProgress();
  void takeBackLeases(WorkerInfo& worker, int64_t stillMs);
  void releaseWorker(const std::string& identity, const std::string& reason);
  JobContext& context(uint64_t job);

  // Within a round, messages wait in the outbox until the round commits.
  void send(const std::string& identity, capnp::MallocMessageBuilder& message,
            net::Encoding encoding = net::Encoding::Packed);
  void transmit(const std::string& identity, zmq::message_t& frame);
  void sendError(const std::string& identity, const std::string& error);
  // One round of the loop: what arrived, timers and scheduling, in one
  // transaction, committed before anything is sent (runRound in coordinator.cpp).
  void runRound();
  // Runs `work` in one transaction; sends what it sent once that commits.
  // False: the round was undone (undoRound).
  bool inRound(const std::function<void()>& work);
  void undoRound();

  CoordinatorOptions options_;
  JobStore store_;
  zmq::context_t zmq_;
  zmq::socket_t router_;
  std::unique_ptr<RouterSecurity> security_;   // after router_: gone before it closes
  uint64_t maxFrameBytes_;
  std::string endpoint_;
  WorkerRegistry workers_;
  std::map<uint64_t, JobContext> jobs_;
  std::atomic<bool> stopping_{false};
  int64_t lastHeartbeatMs_ = 0;
  std::set<std::pair<uint64_t, uint32_t>> failedCells_;   // (job, cell) that failed a lease
  LogThrottle refusals_;   // messages refused for their sender's role: a line a minute per peer and type
  struct Retry {
    int count = 0;              // failures and losses since the cell's last Result
    int64_t notBeforeMs = 0;    // steady clock
  };
  std::map<std::pair<uint64_t, uint32_t>, Retry> retries_;   // (job, cell)
  // Refused Results of each (job, cell) since its last accepted one: which
  // worker sent it and why it was refused.
  struct Refusal {
    std::string worker;
    std::string reason;
  };
  std::map<std::pair<uint64_t, uint32_t>, std::vector<Refusal>> refusedResults_;
  std::map<std::string, int64_t> refusalsByWorker_;   // worker name -> its Results refused, all jobs
  // Cells whose lease was taken back from a worker that stopped moving,
  // until their next accepted Result: from whom, why and when (wall clock).
  struct TakenBack {
    std::string worker;
    std::string reason;
    int64_t atMs = 0;
  };
  std::map<std::pair<uint64_t, uint32_t>, TakenBack> takenBack_;
  static constexpr int64_t kRefusalsBeforeSidelined = 3;
  // Disk trouble: no leasing before diskPausedUntilMs_ (steady clock); the
  // pause doubles with each failed round; requeueUntracedLeases is owed
  // when undoRound could not do it.
  int64_t diskPausedUntilMs_ = 0;
  int64_t diskBackoffMs_ = 0;
  int64_t diskFailures_ = 0;          // failed rounds since the last line logged about them
  int64_t diskLoggedMs_ = 0;
  int64_t diskTroubleSinceMs_ = 0;    // wall clock of the first failed round since writes last succeeded
  int64_t diskRoundsUndone_ = 0;      // since then
  std::string diskTroubleWhat_;       // the last failure, for status
  // Jobs whose store cannot be read: since when (wall clock) and why.
  struct StoreTrouble {
    int64_t sinceMs = 0;
    std::string reason;
  };
  std::map<uint64_t, StoreTrouble> storeTrouble_;
  bool requeueOwed_ = false;
  LogThrottle storeLog_{std::chrono::seconds(10)};
  // The round in progress (inRound): its replies, and the leases it opened
  // (worker identity, lease), for undoing the coordinator's memory if its
  // commit fails; the leases whose Results it applied, which decide where
  // --fail-commits-every strikes.
  bool inRound_ = false;
  int64_t roundTransactions_ = 0;   // rounds that applied Results (fault injection)
  struct Outgoing {
    std::string identity;
    zmq::message_t frame;
    bool refersToRound;   // a lease or a new job's id: void if the round is undone
  };
  std::vector<Outgoing> outbox_;
  std::vector<std::pair<std::string, uint64_t>> roundLeases_;
  std::vector<uint64_t> roundResults_;
  // The leases whose Results arrived this round, as they were sent (the
  // lease log's sent time, work and more cells), until onResult logs them.
  std::map<uint64_t, WorkerInfo::LeaseInFlight> arrivedLeases_;
  // Each photon lease's deposit region until its Result or Failure arrives
  // (coordinator/deposit_regions.h), and the source of their nonces.
  std::unordered_map<uint64_t, DepositRegionGrant> depositRegions_;
  std::mt19937_64 nonceSource_{std::random_device{}()};
  // The coordinator's own work so far, in every status reply (its CPU per
  // lease, for whoever measures it from outside: `portico bench coordinator`).
  int64_t leasesSent_ = 0;
  int64_t resultsApplied_ = 0;
  // The coordinator's own peak resident memory, read at most once a second
  // (a Result's transaction records it in the job's statistics).
  uint64_t peakResident();
  uint64_t peakResident_ = 0;
  int64_t peakResidentReadMs_ = -1000;
};

int64_t nowMs();

}  // namespace portico
