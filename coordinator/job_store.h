// jobs.db: everything the coordinator knows, so that a coordinator killed at
// any moment and restarted on the same file resumes every unfinished job.
// SQLite in WAL mode, owned by the coordinator alone; the caller groups
// calls into transactions (sql::Transaction). The payloads of photon and ray
// batches live in append-only files beside it (append_files.h).
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <set>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <unordered_map>
#include <vector>

#include "common/transport/film.h"
#include "common/util/sqlite.h"
#include "coordinator/append_files.h"
#include "coordinator/cell_work_index.h"
#include "coordinator/counter_table.h"

namespace portico {

enum class JobState { Photons, Render, Done, Failed, Cancelled };
std::string_view toString(JobState state);
JobState jobStateFromString(std::string_view text);
inline bool isActive(JobState s) { return s == JobState::Photons || s == JobState::Render; }
// The batch phase a job in `state` is working on (0 photons, 1 render).
inline int phaseOf(JobState s) { return s == JobState::Render ? 1 : 0; }

enum class BatchKind { Rays = 0, Emit = 1, Camera = 2, Sensors = 3 };

struct JobRecord {
  uint64_t id = 0;
  JobState state = JobState::Photons;
  std::string error;
  std::string spec;            // packed wire::JobSpec
  int64_t createdMs = 0, phaseStartedMs = 0, finishedMs = 0;
  // The size of the records its photon tables hold: sizeof(PhotonRecord)
  // (8 since protocol 21), 16 for a job begun by a portico before it, or 24
  // before schema 5. Each size is one format, so the size tells them apart.
  int photonRecordBytes = 0;
  // What decides its photon tables (photon_reuse.h; "" for none: a job that
  // cannot lend its pass), the earlier job whose tables it renders with (0:
  // its own), and whether its own photon pass is complete.
  std::string photonKey;
  uint64_t photonSource = 0;
  bool photonsComplete = false;
  // The job whose photon tables its render phase reads.
  uint64_t photonJob() const { return photonSource ? photonSource : id; }
  // Scheduling (schema 13): its leases come before those of lower
  // priorities, and go only to workers having every required tag (sorted;
  // common/job/worker_tags.h).
  int priority = 0;
  std::vector<std::string> requiredTags;
  // Who submitted it (schema 14; net::Peer::who), "" for a job of an older
  // schema: with per-user keys only its owner and operators see its paths
  // and log, and steer it (docs/security.md).
  std::string owner;
};

struct PendingCell {
  uint64_t job = 0;
  uint32_t cell = 0;
  int phase = 0;
  int64_t work = 0;
};

struct QueuedBatch {
  int64_t id = 0;
  int64_t work = 0;
  std::string payload;         // packed wire::RayBatch
  uint32_t attempts = 0;       // leases it was in that were lost (their worker died or left)
};

struct LeaseRecord {
  uint64_t id = 0;
  uint64_t job = 0;
  uint32_t cell = 0;
  int phase = 0;
  std::string worker;
  uint32_t attempt = 0;
};

// A completed lease as the coordinator saw it: its cell, work, worker, when
// it was sent and its Result applied, and the worker's own time in it
// (loads included) and in its cell loads; of that time, its tracing
// thread's CPU and its wait for a core (-1: not recorded, a row of schema 8
// or a kernel without schedstat).
struct LeaseLogEntry {
  uint64_t job = 0;
  uint64_t lease = 0;
  int phase = 0;
  uint32_t cell = 0;
  uint32_t moreCells = 0;
  int64_t work = 0;
  std::string worker;
  int64_t sentMs = 0, resultMs = 0;
  int64_t leaseMicros = 0, loadMicros = 0;
  int64_t cellsLoaded = 0, trianglesLoaded = 0;
  int64_t cpuMicros = -1, runQueueMicros = -1;
  // Which more cells, with the work of each (schema 10); false in rows
  // logged before, which count them only.
  bool moreCellsLogged = false;
  std::vector<std::pair<uint32_t, int64_t>> moreCellWork;
};

class JobStore {
 public:
  static constexpr int kSchemaVersion = 14;
  // A job's ray batch file starts a new segment past this size, so that
  // consumed segments can be deleted while the job runs.
  static constexpr int64_t kBatchSegmentBytes = int64_t(256) << 20;
  // batchSegmentBytes: kBatchSegmentBytes but in tests.
  explicit JobStore(const std::string& path, int64_t batchSegmentBytes = kBatchSegmentBytes);
  ~JobStore();

  sql::Database& database() { return db_; }

  uint64_t createJob(const std::string& spec, int64_t nowMs);
  std::optional<JobRecord> job(uint64_t id);
  std::vector<JobRecord> jobs(bool activeOnly);
  void setJobState(uint64_t job, JobState state, int64_t nowMs, const std::string& error = "");
  // Scheduling only: what the job computes stays as it is.
  void setPriority(uint64_t job, int priority);
  void setRequiredTags(uint64_t job, const std::vector<std::string>& tags);
  void setOwner(uint64_t job, const std::string& owner);

  // Photon-pass reuse (photon_reuse.h). At submit: what decides the job's
  // photon tables, and the earlier job whose tables it renders with (0: it
  // runs its own pass).
  void setPhotonPass(uint64_t job, const std::string& key, uint64_t source);
  // The newest job with this key whose own photon pass is complete, that is
  // rendering or done, and whose photon file still holds every batch its
  // rows name; nullopt when there is none.
  std::optional<uint64_t> reusablePhotonPass(const std::string& key);
  void markPhotonPassComplete(uint64_t job);
  // Its photon tables were found damaged: never offered for reuse again.
  void withdrawPhotonPass(uint64_t job);

  // work: rays the batch holds or will generate (the scheduler's measure).
  // The payload goes to the job's batch file at once (a view into a Result
  // will do), its place into jobs.db with the caller's transaction.
  void addBatch(uint64_t job, uint32_t cell, int phase, BatchKind kind, int64_t work, std::string_view payload);
  int64_t queuedRays(uint64_t job, int phase);   // rays in flight between cells
  // Cells with unleased work in their job's current phase: the jobs by
  // priority, highest first (equal priorities: the oldest first), and in
  // each, most work first. `mayTake(requiredTags)`: whether the jobs that
  // require these tags may be leased (to the worker asking); none: all.
  std::vector<PendingCell> pendingCells(
      size_t limit, const std::function<bool(const std::vector<std::string>&)>& mayTake = nullptr);
  // Leases up to maxWork of the oldest unleased batches of (job, cell, phase)
  // (always at least one batch), fills `batches` and returns the lease (id
  // 0: nothing queued for the cell). Its attempt is 1 + the most times any
  // of its batches was in a lost lease: a batch that keeps killing workers
  // shows in the attempt. Throws DamagedFileError when a batch's bytes are
  // lost (then nothing is leased, once the caller's transaction rolls back).
  LeaseRecord openLease(const PendingCell& cell, const std::string& worker, int64_t maxWork, int64_t nowMs,
                        std::vector<QueuedBatch>& batches);
  // An open lease (a closed one, completed or requeued, leaves no row: the
  // table holds open leases only).
  std::optional<LeaseRecord> lease(uint64_t id);
  // Photon pass: another cell's unleased batches (up to maxWork, at least
  // one) join an open lease, which completes or is requeued as one. Returns
  // their work (0: none pending).
  int64_t addToLease(uint64_t lease, const PendingCell& cell, int64_t maxWork, std::vector<QueuedBatch>& batches);
  std::vector<LeaseRecord> openLeasesOf(const std::string& worker);
  std::vector<LeaseRecord> openLeases();
  // The lease's batches are consumed (deleted) and the lease closed (its row deleted).
  void completeLease(uint64_t lease);
  // The lease's batches go back to the queue. `lost`: its worker died or
  // left holding it, which counts against the batches' attempts (a failure
  // the worker reported does not: the job's failure counters track those).
  void requeueLease(uint64_t lease, bool lost = false);
  // Startup: leases held by workers of a previous run go back to the queue
  // (not an attempt of theirs: the coordinator, not the cell, was lost).
  int requeueAllOpenLeases();
  int64_t remainingWork(uint64_t job, int phase);   // queued or leased batches
  bool hasRemainingWork(uint64_t job, int phase);   // remainingWork > 0, without counting
  int64_t openLeaseCount(uint64_t job);
  std::map<uint32_t, int64_t> pendingWorkByCell(uint64_t job, int phase, size_t limit);
  void dropJobWork(uint64_t job);                   // cancel/fail: batches and leases
  // Back to the start of the photon pass: the job's work, photons, film,
  // render passes and counters dropped (its photon file cut back to the
  // end of the last deposit region handed out),
  // state photons, a photon pass of its own (no longer anyone else's, nor
  // complete); the counter kPhotonPassRestarts alone is kept, and
  // incremented. The caller queues the emission again, in the same
  // transaction.
  static constexpr const char* kPhotonPassRestarts = "restarts.photon_pass";
  void restartJob(uint64_t job, int64_t nowMs);

  void addCounter(uint64_t job, std::string_view name, int64_t delta);
  // A counter that keeps the largest value it was given (a peak, not a sum).
  void raiseCounter(uint64_t job, std::string_view name, int64_t value);
  // One row per completed lease (lease_log): what the cluster model
  // (`portico bench cluster`) replays.
  void logLease(const LeaseLogEntry& entry);
  std::vector<LeaseLogEntry> leaseLog(uint64_t job);
  // Read from memory (counter_table.h): no statement.
  std::map<std::string, int64_t> counters(uint64_t job);

  // The payload goes to the job's photon file (append_files.h) at once, its
  // place into jobs.db with the caller's transaction: a view into a Result
  // will do.
  void addPhotons(uint64_t job, uint32_t cell, int64_t count, std::string_view payload);
  // Photons a worker wrote into its lease's deposit region
  // (coordinator/deposit_regions.h): only their place goes into jobs.db.
  void addPhotonsAt(uint64_t job, uint32_t cell, const FileExtent& extent);
  // Sets `size` bytes of the job's photon file aside for a worker to write a
  // lease's deposits into, with `head` at their start, and returns their
  // offset; the end of the region is kept with the caller's transaction, and
  // the file never resumes before it (not after a restart of the
  // coordinator or of the photon pass either).
  int64_t reserveDepositRegion(uint64_t job, int64_t size, std::string_view head);
  // In the order they were added; throws naming the file when one is damaged.
  std::vector<std::string> photonBatches(uint64_t job, uint32_t cell);
  // Where they lie in the job's photon file (photonFile), in the same order,
  // without reading them; none when a batch is a blob of an older schema.
  std::optional<std::vector<FileExtent>> photonExtents(uint64_t job, uint32_t cell);
  std::filesystem::path photonFile(uint64_t job) const { return photons_.pathOf({job, 0}); }
  std::filesystem::path batchFile(uint64_t job, uint32_t segment) const { return batches_.pathOf({job, segment}); }
  // The job's bytes on disk beside jobs.db: its photon file (the blocks it
  // holds: deposit regions leave holes where nothing was written) and its
  // ray batch segments (jobs.db itself is shared by every job).
  struct JobFileBytes {
    int64_t photons = 0, batches = 0;
  };
  JobFileBytes jobFileBytes(uint64_t job) const;
  int64_t databaseBytes() const;   // jobs.db and its WAL

  // Deletes the batch files no row refers to any more: segments a job has
  // moved past, and the files of jobs that ended. Call it outside any
  // transaction (what it reads must be committed), e.g. after each commit;
  // it costs nothing when no file became a candidate.
  void reclaimBatchFiles();

  // An analysis job's sensors (coordinator/analysis_sensors.h), stored
  // whole at submit: the sensor batches of its render phase and its CSV are
  // made from them.
  void setJobSensors(uint64_t job, std::string_view records);
  std::string jobSensors(uint64_t job);

  static constexpr uint32_t kFilmChunkPixels = 4096;
  // Throws FilmRangeError (film.h) when a pixel's sum would leave the film's range.
  void addFilm(uint64_t job, const std::unordered_map<uint32_t, FixedRgb>& sums, uint64_t pixelCount);
  std::vector<FixedRgb> film(uint64_t job, uint64_t pixelCount);

 private:
  void refuseFilesOfUnknownJobs(const std::string& path);
  void migrate();
  void loadUnleasedWork();
  int64_t takeUnleased(const PendingCell& cell, int64_t maxWork, std::vector<QueuedBatch>& batches, uint32_t& attempt);
  void markLeased(uint64_t lease, const PendingCell& cell, const std::vector<QueuedBatch>& batches, int64_t work);
  void rechecksumPhotonFiles();
  // A photon batch's row: where its `count` records lie in the job's file.
  void recordPhotons(uint64_t job, uint32_t cell, int64_t count, const FileExtent& extent);
  bool photonFileHoldsItsBatches(uint64_t job);
  uint32_t batchSegment(uint64_t job);
  void retireBatchSegment(uint64_t job, uint32_t segment);
  sql::Database db_;
  CounterTable counters_{db_};   // observes db_'s transactions (set in the constructor, unset in the destructor)
  AppendFiles photons_;
  AppendFiles batches_;
  // The segment each job appends to (loaded from jobs.db on first use), and
  // files to delete once no committed row refers to them.
  int64_t batchSegmentBytes_;
  std::map<uint64_t, uint32_t> batchSegments_;
  std::set<AppendFiles::Key> reclaimCandidates_;
  // The work per (job, phase, cell) in memory (cell_work_index.h): the
  // unleased, what pendingCells() ranks, and all that is left, leased or
  // not, with the queued rays of each (job, phase), what status shows and
  // what tells a phase's end. Rebuilt from the table at start, after any
  // rollback (sqlite3_rollback_hook, and the database's listener for a
  // nested transaction's) and after the rare bulk changes (requeues,
  // dropped jobs).
  CellWorkIndex unleased_;
  bool unleasedValid_ = false;
  CellWorkIndex remaining_;
  std::map<std::pair<uint64_t, int>, int64_t> queuedRays_;
  bool remainingValid_ = false;
  void loadRemainingWork();
  // The active jobs in pendingCells()'s order, read again after any change
  // of a job's state, priority or tags, and after a rollback: a lease no
  // longer reads the jobs table.
  struct ActiveJob {
    uint64_t id = 0;
    int phase = 0;
    std::vector<std::string> requiredTags;
  };
  std::vector<ActiveJob> activeJobs_;
  bool activeJobsValid_ = false;
  void loadActiveJobs();
  // The jobs read so far (job()), dropped with the active jobs at any change
  // of the jobs table and at any rollback: a Result reads its job's record
  // without a statement.
  std::unordered_map<uint64_t, JobRecord> jobRecords_;
  void jobsChanged();
};

}  // namespace portico
