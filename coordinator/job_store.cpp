#include "coordinator/job_store.h"

#include "common/job/worker_tags.h"
#include "common/transport/photon_record.h"
#include "common/util/crc32c.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <sqlite3.h>
#include <sys/stat.h>
#include <zlib.h>

#include <algorithm>
#include <limits>
#include <cstdio>
#include <cstring>
#include <functional>
#include <stdexcept>
#include <tuple>

namespace portico {

std::string_view toString(JobState state) {
  switch (state) {
    case JobState::Photons: return "photons";
    case JobState::Render: return "render";
    case JobState::Done: return "done";
    case JobState::Failed: return "failed";
    case JobState::Cancelled: return "cancelled";
  }
  return "?";
}

JobState jobStateFromString(std::string_view text) {
  for (JobState s : {JobState::Photons, JobState::Render, JobState::Done, JobState::Failed, JobState::Cancelled})
    if (toString(s) == text) return s;
  throw std::runtime_error(fmt::format("jobs.db: unknown job state '{}'", text));
}

JobStore::JobStore(const std::string& path, int64_t batchSegmentBytes)
    : db_(path, sql::Database::Mode::ReadWriteCreate),
      photons_(path + "-photons", AppendFiles::Naming::PerJob, "photon batch",
               [this](AppendFiles::Key file) {
                 // Past every recorded batch and every deposit region handed out
                 // (a worker may still write into one: deposit_regions.h); a
                 // migration before schema 11 reads files without regions.
                 auto& s = db_.prepare(
                     db_.userVersion() >= 11
                         ? "SELECT MAX(COALESCE((SELECT MAX(file_offset + file_size) FROM photons WHERE job = ?1), 0), "
                           "COALESCE((SELECT photon_region_end FROM jobs WHERE id = ?1), 0))"
                         : "SELECT COALESCE(MAX(file_offset + file_size), 0) FROM photons WHERE job = ?1");
                 s.bind(1, int64_t(file.first));
                 const int64_t end = s.step() ? s.columnInt(0) : 0;
                 s.reset();
                 return end;
               },
               AppendFiles::Caching::Direct),   // written once, read once: append_files.h
      batches_(path + "-batches", AppendFiles::Naming::PerSegment, "ray batch", [this](AppendFiles::Key file) {
        auto& s = db_.prepare(
            "SELECT COALESCE(MAX(file_offset + file_size), 0) FROM batches WHERE job = ? AND file_segment = ?");
        s.bind(1, int64_t(file.first)).bind(2, int64_t(file.second));
        const int64_t end = s.step() ? s.columnInt(0) : 0;
        s.reset();
        return end;
      }),
      batchSegmentBytes_(batchSegmentBytes) {
  // One coordinator per jobs.db, holding it for its whole life: no other
  // process reads or writes it while it runs (status goes through the
  // coordinator's socket). The exclusive locking mode spares every
  // transaction the file locks, and the WAL index lives in the heap rather
  // than in a shared -shm file. A second coordinator on the same jobs.db is
  // refused here, by name, instead of waiting on locks.
  sqlite3_busy_timeout(db_.handle(), 0);   // a lock held by a live process is not let go: fail at once
  try {
    db_.exec("PRAGMA locking_mode = EXCLUSIVE");
    db_.exec("PRAGMA journal_mode = WAL");
    db_.exec("BEGIN IMMEDIATE");
    db_.exec("COMMIT");
  } catch (const sql::Error& e) {
    // Only a lock says "another process"; anything else (not a database, a
    // directory, no permission, a full disk) is said as it is.
    if (e.code == SQLITE_BUSY || e.code == SQLITE_LOCKED)
      throw std::runtime_error(fmt::format(
          "{}: in use by another process (is another coordinator running on it?): {}", path, e.what()));
    throw std::runtime_error(fmt::format("{}: cannot be used as the job database: {}", path, e.what()));
  }
  sqlite3_busy_timeout(db_.handle(), sql::Database::kBusyTimeoutMs);
  // NORMAL is durable across process crashes in WAL mode (only an OS crash
  // can lose the last commits), which is the failure portico guards against.
  db_.exec("PRAGMA synchronous = NORMAL");
  db_.exec("PRAGMA foreign_keys = ON");
  refuseFilesOfUnknownJobs(path);
  migrate();
  sqlite3_rollback_hook(
      db_.handle(),
      [](void* store) {
        auto* self = static_cast<JobStore*>(store);
        self->unleasedValid_ = self->remainingValid_ = false;
        self->jobsChanged();
      },
      this);
  // The hook misses a nested transaction's partial rollback (a savepoint).
  db_.setRollbackListener([this] {
    unleasedValid_ = remainingValid_ = false;
    jobsChanged();
  });
  db_.setObserver(&counters_);
  // Files left by an earlier run: those no row refers to go.
  for (const AppendFiles::Key& file : batches_.filesOnDisk()) reclaimCandidates_.insert(file);
  reclaimBatchFiles();
}

JobStore::~JobStore() { db_.setObserver(nullptr); }

// Files of jobs that jobs.db does not hold mean, in general, that jobs.db
// lost its last commits (its -wal file deleted, the file truncated or
// replaced by an older copy). Starting anyway would forget those jobs and
// delete their files; refusing keeps everything for the operator to
// restore. One case is innocent: a coordinator killed while it queued new
// jobs leaves the first ray segment of each (written before the
// transaction that would have created them), for the ids after the last
// job: those are deleted at start as before.
void JobStore::refuseFilesOfUnknownJobs(const std::string& path) {
  const std::vector<AppendFiles::Key> photonFiles = photons_.filesOnDisk(), batchFiles = batches_.filesOnDisk();
  if (photonFiles.empty() && batchFiles.empty()) return;
  const bool schema = db_.userVersion() > 0;   // an empty (new or truncated) file has no tables
  std::set<uint64_t> known;
  if (schema) {
    auto& s = db_.prepare("SELECT id FROM jobs");
    while (s.step()) known.insert(uint64_t(s.columnInt(0)));
    s.reset();
  }
  const uint64_t lastKnown = known.empty() ? 0 : *known.rbegin();
  std::set<uint64_t> unknown;
  bool lost = !schema;
  for (const AppendFiles::Key& file : photonFiles)
    if (!known.count(file.first)) unknown.insert(file.first), lost = true;   // photons come from committed Results
  for (const AppendFiles::Key& file : batchFiles)
    if (!known.count(file.first)) unknown.insert(file.first), lost = lost || file.second > 0;
  // A killed submit leaves the ids right after the last job, without gaps.
  uint64_t expected = lastKnown + 1;
  for (uint64_t job : unknown) lost = lost || job != expected++;
  if (unknown.empty() || !lost) return;
  const size_t shown = std::min<size_t>(unknown.size(), 10);
  throw std::runtime_error(fmt::format(
      "{} holds {} jobs, but {}-photons/ and {}-batches/ hold files of {} jobs it does not have (job {}{}): jobs.db "
      "lost its last commits (its -wal file deleted, the file truncated or replaced by an older copy). Nothing was "
      "changed or deleted. Restore jobs.db together with its jobs.db-wal from the same backup; or, to drop those "
      "jobs' photons and queued rays for good, move {}-photons/ and {}-batches/ away and start again",
      path, known.size(), path, path, unknown.size(),
      fmt::join(std::vector<uint64_t>(unknown.begin(), std::next(unknown.begin(), std::ptrdiff_t(shown))), ", "),
      unknown.size() > shown ? ", ..." : "", path, path));
}

void JobStore::loadUnleasedWork() {
  unleased_.clear();
  auto& s = db_.prepare(
      "SELECT job, phase, cell, SUM(work), COUNT(*) FROM batches WHERE lease IS NULL GROUP BY job, phase, cell");
  while (s.step())
    unleased_.change(uint64_t(s.columnInt(0)), int(s.columnInt(1)), uint32_t(s.columnInt(2)), s.columnInt(3),
                     s.columnInt(4));
  s.reset();
  unleasedValid_ = true;
}

void JobStore::loadRemainingWork() {
  remaining_.clear();
  queuedRays_.clear();
  auto& s = db_.prepare(
      "SELECT job, phase, cell, SUM(work), COUNT(*), SUM(work) FILTER (WHERE kind = 0) FROM batches "
      "GROUP BY job, phase, cell");
  while (s.step()) {
    const uint64_t job = uint64_t(s.columnInt(0));
    const int phase = int(s.columnInt(1));
    remaining_.change(job, phase, uint32_t(s.columnInt(2)), s.columnInt(3), s.columnInt(4));
    if (const int64_t rays = s.columnInt(5); rays != 0) queuedRays_[{job, phase}] += rays;
  }
  s.reset();
  remainingValid_ = true;
}

namespace {
// The schema's steps, one per version: a database at version v runs steps
// v+1..latest (JobStore::migrate).

// Version 1: jobs, their queued batches, open leases, photon tables, film
// chunks and counters.
constexpr const char* kSchemaVersion1 = R"sql(
      CREATE TABLE jobs (
        id INTEGER PRIMARY KEY,
        spec BLOB NOT NULL,
        state TEXT NOT NULL,
        error TEXT NOT NULL DEFAULT '',
        created_ms INTEGER NOT NULL,
        phase_started_ms INTEGER NOT NULL,
        finished_ms INTEGER NOT NULL DEFAULT 0
      );
      CREATE TABLE batches (
        id INTEGER PRIMARY KEY,
        job INTEGER NOT NULL REFERENCES jobs(id),
        cell INTEGER NOT NULL,
        phase INTEGER NOT NULL,
        lease INTEGER,
        kind INTEGER NOT NULL,       -- 0 rays, 1 photon emission, 2 camera rays
        work INTEGER NOT NULL,
        payload BLOB NOT NULL
      );
      CREATE INDEX batches_by_cell ON batches(job, phase, cell, lease);
      CREATE INDEX batches_by_lease ON batches(lease);
      CREATE TABLE leases (
        id INTEGER PRIMARY KEY,
        job INTEGER NOT NULL REFERENCES jobs(id),
        cell INTEGER NOT NULL,
        phase INTEGER NOT NULL,
        worker TEXT NOT NULL,
        attempt INTEGER NOT NULL,
        started_ms INTEGER NOT NULL,
        state TEXT NOT NULL
      );
      CREATE INDEX leases_open ON leases(state, worker);
      CREATE TABLE photons (
        id INTEGER PRIMARY KEY,
        job INTEGER NOT NULL REFERENCES jobs(id),
        cell INTEGER NOT NULL,
        count INTEGER NOT NULL,
        payload BLOB NOT NULL
      );
      CREATE INDEX photons_by_cell ON photons(job, cell);
      CREATE TABLE film (
        job INTEGER NOT NULL REFERENCES jobs(id),
        chunk INTEGER NOT NULL,
        payload BLOB NOT NULL,
        PRIMARY KEY (job, chunk)
      );
      CREATE TABLE counters (
        job INTEGER NOT NULL REFERENCES jobs(id),
        name TEXT NOT NULL,
        value INTEGER NOT NULL,
        PRIMARY KEY (job, name)
      );
    )sql";

// Version 2: attempt numbers, how many lost leases each queued batch has been in.
constexpr const char* kSchemaVersion2 = "ALTER TABLE batches ADD COLUMN attempts INTEGER NOT NULL DEFAULT 0";

// Version 3: photon payloads live in append-only files (append_files.h);
// rows keep where each lies. Rows of version 2 keep their blob (file_offset NULL).
constexpr const char* kSchemaVersion3 = R"sql(
      ALTER TABLE photons ADD COLUMN file_offset INTEGER;
      ALTER TABLE photons ADD COLUMN file_size INTEGER NOT NULL DEFAULT 0;
      ALTER TABLE photons ADD COLUMN file_crc INTEGER NOT NULL DEFAULT 0;
    )sql";

// Version 4, first part: ray batch payloads live in append-only files too
// (rows of version 3 keep their blob: file_segment NULL).
constexpr const char* kSchemaVersion4Batches = R"sql(
      ALTER TABLE batches ADD COLUMN file_segment INTEGER;
      ALTER TABLE batches ADD COLUMN file_offset INTEGER NOT NULL DEFAULT 0;
      ALTER TABLE batches ADD COLUMN file_size INTEGER NOT NULL DEFAULT 0;
      ALTER TABLE batches ADD COLUMN file_crc INTEGER NOT NULL DEFAULT 0;
    )sql";

// Version 4, second part: closed leases leave no row. The table holds the
// open ones, a handful, and needs no index (two fewer index updates per
// lease); its state column stays as version 3 has it, 'open' in every row.
// Ids must still never repeat (a late Result names its lease by id):
// AUTOINCREMENT, from the highest id ever given.
constexpr const char* kSchemaVersion4Leases = R"sql(
      CREATE TABLE leases_v4 (
        id INTEGER PRIMARY KEY AUTOINCREMENT,
        job INTEGER NOT NULL REFERENCES jobs(id),
        cell INTEGER NOT NULL,
        phase INTEGER NOT NULL,
        worker TEXT NOT NULL,
        attempt INTEGER NOT NULL,
        started_ms INTEGER NOT NULL,
        state TEXT NOT NULL
      );
      INSERT INTO leases_v4 SELECT id, job, cell, phase, worker, attempt, started_ms, state FROM leases
        WHERE state = 'open';
      DELETE FROM sqlite_sequence WHERE name = 'leases_v4';
      INSERT INTO sqlite_sequence(name, seq) SELECT 'leases_v4', COALESCE(MAX(id), 0) FROM leases;
      DROP TABLE leases;
      ALTER TABLE leases_v4 RENAME TO leases;
    )sql";

// Version 5: each job says which photon records its tables hold: 24 bytes
// of floats (versions up to 4), or 16 on a lattice over each cell
// (common/transport/photon_record.h). The coordinator runs the photon pass
// of an unfinished job with 24-byte records again (Coordinator's constructor).
constexpr const char* kSchemaVersion5 =
    "ALTER TABLE jobs ADD COLUMN photon_record_bytes INTEGER NOT NULL DEFAULT 24";

// Version 6: photon-pass reuse (coordinator/photon_reuse.h). Each job keeps
// what decides its photon tables (store, its content, photon settings), the
// earlier job whose tables it renders with (0: its own), and whether its own
// pass is complete. Jobs of older versions lend nothing (no key).
constexpr const char* kSchemaVersion6 = R"sql(
      ALTER TABLE jobs ADD COLUMN photon_key TEXT NOT NULL DEFAULT '';
      ALTER TABLE jobs ADD COLUMN photon_source INTEGER NOT NULL DEFAULT 0;
      ALTER TABLE jobs ADD COLUMN photons_complete INTEGER NOT NULL DEFAULT 0;
      UPDATE jobs SET photons_complete = 1 WHERE state IN ('render', 'done');
      CREATE INDEX jobs_by_photon_key ON jobs(photon_key) WHERE photon_key != '';
    )sql";
// Version 7: render passes (coordinator/render_passes.h). A job in its
// render phase without a render_progress row renders its one pass.
constexpr const char* kSchemaVersion7 = R"sql(
      CREATE TABLE render_progress (
        job INTEGER PRIMARY KEY REFERENCES jobs(id),
        passes_started INTEGER NOT NULL,
        stop_reason TEXT NOT NULL DEFAULT '',
        block_sums BLOB,
        block_deviations BLOB
      );
      CREATE TABLE render_passes (
        job INTEGER NOT NULL REFERENCES jobs(id),
        pass INTEGER NOT NULL,
        finished_ms INTEGER NOT NULL,
        error_estimate REAL,
        PRIMARY KEY (job, pass)
      );
    )sql";
// Version 8: the lease log, one row per completed lease (LeaseLogEntry),
// for the cluster model; a few dozen bytes per lease.
constexpr const char* kSchemaVersion8 = R"sql(
      CREATE TABLE lease_log (
        job INTEGER NOT NULL REFERENCES jobs(id),
        lease INTEGER NOT NULL,
        phase INTEGER NOT NULL,
        cell INTEGER NOT NULL,
        more_cells INTEGER NOT NULL,
        work INTEGER NOT NULL,
        worker TEXT NOT NULL,
        sent_ms INTEGER NOT NULL,
        result_ms INTEGER NOT NULL,
        lease_us INTEGER NOT NULL,
        load_us INTEGER NOT NULL,
        cells_loaded INTEGER NOT NULL,
        triangles_loaded INTEGER NOT NULL
      );
      CREATE INDEX lease_log_by_job ON lease_log(job);
    )sql";
// Version 9: each lease's CPU on its worker and its wait for a core (NULL
// in rows logged before).
constexpr const char* kSchemaVersion9 = R"sql(
      ALTER TABLE lease_log ADD COLUMN cpu_us INTEGER;
      ALTER TABLE lease_log ADD COLUMN run_queue_us INTEGER;
    )sql";
// Version 10: each lease's more cells and their work, "cell:work ..." (NULL
// in rows logged before), so that the cluster model knows every cell a
// lease touched.
constexpr const char* kSchemaVersion10 = "ALTER TABLE lease_log ADD COLUMN more_cell_work TEXT";
// Version 11: the end of the last deposit region set aside in each job's
// photon file (coordinator/deposit_regions.h).
constexpr const char* kSchemaVersion11 = "ALTER TABLE jobs ADD COLUMN photon_region_end INTEGER NOT NULL DEFAULT 0";
// Version 12: lighting analysis, each analysis job's sensors (fixed-size
// records, coordinator/analysis_sensors.h).
constexpr const char* kSchemaVersion12 = R"sql(
      CREATE TABLE job_sensors (
        job INTEGER PRIMARY KEY REFERENCES jobs(id),
        records BLOB NOT NULL
      );
    )sql";
// Version 13: priorities and worker pools. Each job's priority (jobs of
// older versions: 0, as they were scheduled) and the tags its workers must
// have, space-separated ("": any worker).
constexpr const char* kSchemaVersion13 = R"sql(
      ALTER TABLE jobs ADD COLUMN priority INTEGER NOT NULL DEFAULT 0;
      ALTER TABLE jobs ADD COLUMN required_tags TEXT NOT NULL DEFAULT '';
    )sql";
// Version 14: each job's owner, who submitted it (net::Peer::who: "key:Z85"
// or "uid:N"); jobs of older versions have none ('': docs/security.md says
// who sees them).
constexpr const char* kSchemaVersion14 = "ALTER TABLE jobs ADD COLUMN owner TEXT NOT NULL DEFAULT ''";

// LeaseLogEntry::moreCellWork as its column holds it, and back.
std::string moreCellWorkText(const std::vector<std::pair<uint32_t, int64_t>>& cells) {
  std::string text;
  for (const auto& [cell, work] : cells) text += fmt::format("{}{}:{}", text.empty() ? "" : " ", cell, work);
  return text;
}
std::vector<std::pair<uint32_t, int64_t>> moreCellWorkOf(const std::string& text) {
  std::vector<std::pair<uint32_t, int64_t>> cells;
  unsigned long cell = 0;
  long long work = 0;
  int used = 0;
  for (const char* at = text.c_str(); std::sscanf(at, " %lu:%lld%n", &cell, &work, &used) == 2; at += used)
    cells.emplace_back(uint32_t(cell), int64_t(work));
  return cells;
}
}  // namespace

void JobStore::migrate() {
  const int version = db_.userVersion();
  if (version > kSchemaVersion)
    throw std::runtime_error(fmt::format("{}: schema version {} is newer than this coordinator ({}); upgrade portico",
                                         db_.path(), version, kSchemaVersion));
  // Steps fall through, each in its own transaction.
  const auto step = [&](int to, const std::function<void()>& apply) {
    if (version >= to) return;
    sql::Transaction tx(db_);
    apply();
    db_.setUserVersion(to);
    tx.commit();
  };
  step(1, [&] { db_.exec(kSchemaVersion1); });
  step(2, [&] { db_.exec(kSchemaVersion2); });
  step(3, [&] { db_.exec(kSchemaVersion3); });
  step(4, [&] {
    db_.exec(kSchemaVersion4Batches);
    rechecksumPhotonFiles();   // the files' checksum is CRC-32C (hardware on x86-64)
    db_.exec(kSchemaVersion4Leases);
  });
  step(5, [&] { db_.exec(kSchemaVersion5); });
  step(6, [&] { db_.exec(kSchemaVersion6); });
  step(7, [&] { db_.exec(kSchemaVersion7); });
  step(8, [&] { db_.exec(kSchemaVersion8); });
  step(9, [&] { db_.exec(kSchemaVersion9); });
  step(10, [&] { db_.exec(kSchemaVersion10); });
  step(11, [&] { db_.exec(kSchemaVersion11); });
  step(12, [&] { db_.exec(kSchemaVersion12); });
  step(13, [&] { db_.exec(kSchemaVersion13); });
  step(14, [&] { db_.exec(kSchemaVersion14); });
}

// Schema 3 -> 4: each photon batch's zlib CRC-32 is checked and replaced by
// its CRC-32C. A batch that is already damaged (or unreadable) gets a CRC no
// read will match, so that it is still reported as damaged, never blessed.
void JobStore::rechecksumPhotonFiles() {
  struct Row {
    int64_t id;
    uint64_t job;
    FileExtent extent;
  };
  std::vector<Row> rows;
  auto& select = db_.prepare(
      "SELECT id, job, file_offset, file_size, file_crc FROM photons WHERE file_offset IS NOT NULL ORDER BY id");
  while (select.step())
    rows.push_back({select.columnInt(0), uint64_t(select.columnInt(1)),
                    {select.columnInt(2), select.columnInt(3), uint32_t(select.columnInt(4))}});
  select.reset();
  auto& update = db_.prepare("UPDATE photons SET file_crc = ? WHERE id = ?");
  for (const Row& row : rows) {
    uint32_t crc;
    try {
      const std::string bytes = photons_.readUnchecked({row.job, 0}, row.extent);
      const uint32_t zlibCrc =
          uint32_t(crc32(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(bytes.data()), uInt(bytes.size())));
      crc = crc32c(bytes.data(), bytes.size());
      if (zlibCrc != row.extent.crc) crc = ~crc;
    } catch (const DamagedFileError&) {
      crc = ~row.extent.crc;   // past the end: the read fails anyway
    }
    update.bind(1, int64_t(crc)).bind(2, row.id);
    update.run();
  }
  for (const Row& row : rows) photons_.forget({row.job, 0});
}

uint64_t JobStore::createJob(const std::string& spec, int64_t nowMs) {
  jobsChanged();
  auto& s = db_.prepare(
      "INSERT INTO jobs(spec, state, created_ms, phase_started_ms, photon_record_bytes) VALUES (?, ?, ?, ?, ?)");
  s.bindBlob(1, spec.data(), spec.size()).bind(2, toString(JobState::Photons)).bind(3, nowMs).bind(4, nowMs);
  s.bind(5, int64_t(sizeof(PhotonRecord)));
  s.run();
  return static_cast<uint64_t>(db_.lastInsertRowId());
}

void JobStore::setPriority(uint64_t job, int priority) {
  jobsChanged();
  auto& s = db_.prepare("UPDATE jobs SET priority = ? WHERE id = ?");
  s.bind(1, int64_t(priority)).bind(2, int64_t(job));
  s.run();
}

void JobStore::setOwner(uint64_t job, const std::string& owner) {
  jobsChanged();
  auto& s = db_.prepare("UPDATE jobs SET owner = ? WHERE id = ?");
  s.bind(1, owner).bind(2, int64_t(job));
  s.run();
}

void JobStore::setRequiredTags(uint64_t job, const std::vector<std::string>& tags) {
  jobsChanged();
  auto& s = db_.prepare("UPDATE jobs SET required_tags = ? WHERE id = ?");
  s.bind(1, joinTags(tags)).bind(2, int64_t(job));
  s.run();
}

namespace {
JobRecord readJob(sql::Statement& s) {
  JobRecord job;
  job.id = s.columnInt(0);
  job.state = jobStateFromString(s.columnText(1));
  job.error = s.columnText(2);
  auto blob = s.columnBlob(3);
  job.spec.assign(reinterpret_cast<const char*>(blob.data()), blob.size());
  job.createdMs = s.columnInt(4);
  job.phaseStartedMs = s.columnInt(5);
  job.finishedMs = s.columnInt(6);
  job.photonRecordBytes = int(s.columnInt(7));
  job.photonKey = s.columnText(8);
  job.photonSource = uint64_t(s.columnInt(9));
  job.photonsComplete = s.columnInt(10) != 0;
  job.priority = int(s.columnInt(11));
  job.requiredTags = splitTags(s.columnText(12));
  job.owner = s.columnText(13);
  return job;
}
constexpr const char* kJobColumns =
    "id, state, error, spec, created_ms, phase_started_ms, finished_ms, photon_record_bytes, photon_key, "
    "photon_source, photons_complete, priority, required_tags, owner";
}  // namespace

std::optional<JobRecord> JobStore::job(uint64_t id) {
  if (auto cached = jobRecords_.find(id); cached != jobRecords_.end()) return cached->second;
  static const std::string kSelect = fmt::format("SELECT {} FROM jobs WHERE id = ?", kJobColumns);
  auto& s = db_.prepare(kSelect);
  s.bind(1, int64_t(id));
  std::optional<JobRecord> result;
  if (s.step()) result = readJob(s);
  s.reset();
  if (result) jobRecords_.emplace(id, *result);
  return result;
}

void JobStore::jobsChanged() {
  activeJobsValid_ = false;
  jobRecords_.clear();
}

std::vector<JobRecord> JobStore::jobs(bool activeOnly) {
  auto& s = db_.prepare(fmt::format("SELECT {} FROM jobs {} ORDER BY id", kJobColumns,
                                    activeOnly ? "WHERE state IN ('photons', 'render')" : ""));
  std::vector<JobRecord> result;
  while (s.step()) result.push_back(readJob(s));
  s.reset();
  return result;
}

void JobStore::setJobState(uint64_t job, JobState state, int64_t nowMs, const std::string& error) {
  jobsChanged();
  const bool finished = !isActive(state);
  if (finished) {
    // Its batch files go once the end is committed (reclaimBatchFiles); a
    // rollback that keeps the job alive reopens them where they stood.
    const auto segment = batchSegments_.find(job);
    if (segment != batchSegments_.end()) {
      retireBatchSegment(job, segment->second);
      batchSegments_.erase(segment);
    }
  }
  auto& s = db_.prepare(
      "UPDATE jobs SET state = ?, error = ?, phase_started_ms = ?, finished_ms = ? WHERE id = ?");
  s.bind(1, toString(state)).bind(2, error).bind(3, nowMs).bind(4, finished ? nowMs : int64_t(0)).bind(5, int64_t(job));
  s.run();
}

void JobStore::setPhotonPass(uint64_t job, const std::string& key, uint64_t source) {
  jobsChanged();
  auto& s = db_.prepare("UPDATE jobs SET photon_key = ?, photon_source = ? WHERE id = ?");
  s.bind(1, key).bind(2, int64_t(source)).bind(3, int64_t(job));
  s.run();
}

std::optional<uint64_t> JobStore::reusablePhotonPass(const std::string& key) {
  if (key.empty()) return std::nullopt;
  std::vector<uint64_t> candidates;
  auto& s = db_.prepare(
      "SELECT id FROM jobs WHERE photon_key = ? AND photon_source = 0 AND photons_complete = 1 "
      "AND state IN ('render', 'done') AND photon_record_bytes = ? ORDER BY id DESC");
  s.bind(1, key).bind(2, int64_t(sizeof(PhotonRecord)));
  while (s.step()) candidates.push_back(uint64_t(s.columnInt(0)));
  s.reset();
  for (uint64_t job : candidates)
    if (photonFileHoldsItsBatches(job)) return job;
  return std::nullopt;
}

// Cheap: the file is there and long enough for every batch its rows name.
// Each batch's CRC is checked when a worker fetches it (photonBatches).
bool JobStore::photonFileHoldsItsBatches(uint64_t job) {
  auto& s = db_.prepare(
      "SELECT COALESCE(MAX(file_offset + file_size), 0), COUNT(*) FILTER (WHERE file_offset IS NULL) "
      "FROM photons WHERE job = ?");
  s.bind(1, int64_t(job));
  s.step();
  const int64_t end = s.columnInt(0), blobs = s.columnInt(1);
  s.reset();
  if (blobs > 0) return false;   // tables of an older schema: not lent
  if (end == 0) return true;
  std::error_code error;
  const auto size = std::filesystem::file_size(photons_.pathOf({job, 0}), error);
  return !error && int64_t(size) >= end;
}

void JobStore::markPhotonPassComplete(uint64_t job) {
  jobsChanged();
  auto& s = db_.prepare("UPDATE jobs SET photons_complete = 1 WHERE id = ?");
  s.bind(1, int64_t(job));
  s.run();
}

void JobStore::withdrawPhotonPass(uint64_t job) {
  jobsChanged();
  auto& s = db_.prepare("UPDATE jobs SET photon_key = '' WHERE id = ?");
  s.bind(1, int64_t(job));
  s.run();
}

uint32_t JobStore::batchSegment(uint64_t job) {
  if (auto it = batchSegments_.find(job); it != batchSegments_.end()) return it->second;
  // The last segment a committed row refers to; later ones (rolled to, then
  // emptied, before a restart) were deleted at start.
  auto& s = db_.prepare("SELECT COALESCE(MAX(file_segment), 0) FROM batches WHERE job = ?");
  s.bind(1, int64_t(job));
  const uint32_t segment = s.step() ? uint32_t(s.columnInt(0)) : 0;
  s.reset();
  return batchSegments_[job] = segment;
}

// No more writes to the segment: closed, and deleted by reclaimBatchFiles
// once no committed row refers to it.
void JobStore::retireBatchSegment(uint64_t job, uint32_t segment) {
  batches_.forget({job, segment});
  reclaimCandidates_.insert({job, segment});
}

void JobStore::addBatch(uint64_t job, uint32_t cell, int phase, BatchKind kind, int64_t work,
                        std::string_view payload) {
  const uint32_t segment = batchSegment(job);
  const FileExtent extent = batches_.append({job, segment}, payload);
  auto& s = db_.prepare(
      "INSERT INTO batches(job, cell, phase, kind, work, payload, file_segment, file_offset, file_size, file_crc) "
      "VALUES (?, ?, ?, ?, ?, x'', ?, ?, ?, ?)");
  s.bind(1, int64_t(job)).bind(2, int64_t(cell)).bind(3, int64_t(phase)).bind(4, int64_t(kind)).bind(5, work);
  s.bind(6, int64_t(segment)).bind(7, extent.offset).bind(8, extent.size).bind(9, int64_t(extent.crc));
  s.run();
  if (batches_.end({job, segment}) >= batchSegmentBytes_) {
    // The next batch opens a new segment; this one goes once its rows are consumed.
    retireBatchSegment(job, segment);
    batchSegments_[job] = segment + 1;
  }
  if (unleasedValid_) unleased_.change(job, phase, cell, work, 1);
  if (remainingValid_) {
    remaining_.change(job, phase, cell, work, 1);
    if (kind == BatchKind::Rays) queuedRays_[{job, phase}] += work;
  }
}

int64_t JobStore::queuedRays(uint64_t job, int phase) {
  if (!remainingValid_) loadRemainingWork();
  const auto it = queuedRays_.find({job, phase});
  return it == queuedRays_.end() ? 0 : it->second;
}

std::vector<PendingCell> JobStore::pendingCells(
    size_t limit, const std::function<bool(const std::vector<std::string>&)>& mayTake) {
  if (!unleasedValid_) loadUnleasedWork();
  if (!activeJobsValid_) loadActiveJobs();
  std::vector<std::pair<uint64_t, int>> activePhase;
  for (const ActiveJob& job : activeJobs_)
    if (!mayTake || mayTake(job.requiredTags)) activePhase.emplace_back(job.id, job.phase);
  // The highest priority first, the oldest job of equal ones; in a job,
  // most work first (ties: lower cell): the ranked index's order, read no
  // further than `limit` (a tower's 18 K cells with work are not sorted
  // for each lease).
  std::vector<PendingCell> result;
  for (const auto& [job, phase] : activePhase) {
    if (result.size() >= limit) break;
    unleased_.visitRanked(job, phase, [&, job = job, phase = phase](uint32_t cell, int64_t work) {
      result.push_back({job, cell, phase, work});
      return result.size() < limit;
    });
  }
  return result;
}

void JobStore::loadActiveJobs() {
  activeJobs_.clear();
  auto& s = db_.prepare(
      "SELECT id, state, required_tags FROM jobs WHERE state IN ('photons', 'render') ORDER BY priority DESC, id");
  while (s.step())
    activeJobs_.push_back(
        {uint64_t(s.columnInt(0)), phaseOf(jobStateFromString(s.columnText(1))), splitTags(s.columnText(2))});
  s.reset();
  activeJobsValid_ = true;
}

// The cell's unleased batches, oldest first, up to maxWork (at least one).
// Returns their work; `attempt` is one more than the most attempts any had.
int64_t JobStore::takeUnleased(const PendingCell& cell, int64_t maxWork, std::vector<QueuedBatch>& batches,
                               uint32_t& attempt) {
  // Where each batch lies first (rows of schema version 3 and older hold it
  // as a blob), then the reads, so that a damaged file leaves no statement open.
  auto& select = db_.prepare(
      "SELECT id, work, attempts, file_segment IS NULL, payload, file_segment, file_offset, file_size, file_crc "
      "FROM batches WHERE job = ? AND phase = ? AND cell = ? AND lease IS NULL ORDER BY id");
  select.bind(1, int64_t(cell.job)).bind(2, int64_t(cell.phase)).bind(3, int64_t(cell.cell));
  const size_t first = batches.size();
  struct Place {
    uint32_t segment;
    FileExtent extent;
  };
  std::vector<std::optional<Place>> places;   // of each batch taken; none: its blob is in the row
  int64_t total = 0;
  while (select.step()) {
    const int64_t work = select.columnInt(1);
    if (batches.size() > first && total + work > maxWork) break;
    const uint32_t attempts = uint32_t(select.columnInt(2));
    QueuedBatch& batch = batches.emplace_back(QueuedBatch{select.columnInt(0), work, {}, attempts});
    if (select.columnInt(3) != 0) {
      auto blob = select.columnBlob(4);
      batch.payload.assign(reinterpret_cast<const char*>(blob.data()), blob.size());
      places.emplace_back();
    } else {
      places.push_back(Place{uint32_t(select.columnInt(5)),
                             {select.columnInt(6), select.columnInt(7), uint32_t(select.columnInt(8))}});
    }
    attempt = std::max(attempt, attempts + 1);
    total += work;
  }
  select.reset();
  for (size_t i = 0; i < places.size(); ++i)
    if (places[i]) batches[first + i].payload = batches_.read({cell.job, places[i]->segment}, places[i]->extent);
  return total;
}

// Marks the batches as the lease's, and takes them out of the cell's unleased work.
void JobStore::markLeased(uint64_t lease, const PendingCell& cell, const std::vector<QueuedBatch>& batches,
                          int64_t work) {
  // They are the cell's oldest unleased batches (takeUnleased): those up to
  // the last one's id, one statement whatever their number.
  auto& mark = db_.prepare(
      "UPDATE batches SET lease = ? WHERE job = ? AND phase = ? AND cell = ? AND lease IS NULL AND id <= ?");
  mark.bind(1, int64_t(lease)).bind(2, int64_t(cell.job)).bind(3, int64_t(cell.phase)).bind(4, int64_t(cell.cell));
  mark.bind(5, batches.back().id);
  mark.run();
  if (unleasedValid_) unleased_.change(cell.job, cell.phase, cell.cell, -work, -int64_t(batches.size()));
}

LeaseRecord JobStore::openLease(const PendingCell& cell, const std::string& worker, int64_t maxWork, int64_t nowMs,
                                std::vector<QueuedBatch>& batches) {
  batches.clear();
  uint32_t attempt = 1;
  const int64_t total = takeUnleased(cell, maxWork, batches, attempt);
  if (batches.empty()) return {};
  auto& insert = db_.prepare(
      "INSERT INTO leases(job, cell, phase, worker, attempt, started_ms, state) VALUES (?, ?, ?, ?, ?, ?, 'open')");
  insert.bind(1, int64_t(cell.job)).bind(2, int64_t(cell.cell)).bind(3, int64_t(cell.phase)).bind(4, worker);
  insert.bind(5, int64_t(attempt)).bind(6, nowMs);
  insert.run();
  const uint64_t lease = db_.lastInsertRowId();
  markLeased(lease, cell, batches, total);
  return {lease, cell.job, cell.cell, cell.phase, worker, attempt};
}

int64_t JobStore::addToLease(uint64_t lease, const PendingCell& cell, int64_t maxWork,
                             std::vector<QueuedBatch>& batches) {
  batches.clear();
  uint32_t attempt = 1;
  const int64_t total = takeUnleased(cell, maxWork, batches, attempt);
  if (!batches.empty()) markLeased(lease, cell, batches, total);
  return total;
}

namespace {
LeaseRecord readLease(sql::Statement& s) {
  return {uint64_t(s.columnInt(0)), uint64_t(s.columnInt(1)), uint32_t(s.columnInt(2)), int(s.columnInt(3)),
          s.columnText(4), uint32_t(s.columnInt(5))};
}
}  // namespace

std::optional<LeaseRecord> JobStore::lease(uint64_t id) {
  auto& s = db_.prepare("SELECT id, job, cell, phase, worker, attempt FROM leases WHERE id = ?");
  s.bind(1, int64_t(id));
  std::optional<LeaseRecord> result;
  if (s.step()) result = readLease(s);
  s.reset();
  return result;
}

std::vector<LeaseRecord> JobStore::openLeasesOf(const std::string& worker) {
  auto& s = db_.prepare(
      "SELECT id, job, cell, phase, worker, attempt FROM leases WHERE worker = ?");
  s.bind(1, worker);
  std::vector<LeaseRecord> result;
  while (s.step()) result.push_back(readLease(s));
  s.reset();
  return result;
}

std::vector<LeaseRecord> JobStore::openLeases() {
  auto& s = db_.prepare("SELECT id, job, cell, phase, worker, attempt FROM leases");
  std::vector<LeaseRecord> result;
  while (s.step()) result.push_back(readLease(s));
  s.reset();
  return result;
}

void JobStore::completeLease(uint64_t lease) {
  auto& del = db_.prepare("DELETE FROM batches WHERE lease = ? RETURNING job, phase, cell, kind, work");
  del.bind(1, int64_t(lease));
  while (del.step())
    if (remainingValid_) {
      const uint64_t job = uint64_t(del.columnInt(0));
      const int phase = int(del.columnInt(1));
      remaining_.change(job, phase, uint32_t(del.columnInt(2)), -del.columnInt(4), -1);
      if (del.columnInt(3) == int64_t(BatchKind::Rays)) queuedRays_[{job, phase}] -= del.columnInt(4);
    }
  del.reset();
  auto& close = db_.prepare("DELETE FROM leases WHERE id = ?");
  close.bind(1, int64_t(lease));
  close.run();
}

void JobStore::requeueLease(uint64_t lease, bool lost) {
  unleasedValid_ = false;   // rare: recount at the next pendingCells()
  auto& release = db_.prepare("UPDATE batches SET lease = NULL, attempts = attempts + ? WHERE lease = ?");
  release.bind(1, int64_t(lost ? 1 : 0)).bind(2, int64_t(lease));
  release.run();
  auto& close = db_.prepare("DELETE FROM leases WHERE id = ?");
  close.bind(1, int64_t(lease));
  close.run();
}

int JobStore::requeueAllOpenLeases() {
  unleasedValid_ = false;
  sql::Transaction tx(db_);
  db_.exec("UPDATE batches SET lease = NULL WHERE lease IS NOT NULL");
  db_.exec("DELETE FROM leases");
  const int changed = static_cast<int>(db_.changes());
  tx.commit();
  return changed;
}

int64_t JobStore::remainingWork(uint64_t job, int phase) {
  auto& s = db_.prepare("SELECT COUNT(*) FROM batches WHERE job = ? AND phase = ?");
  s.bind(1, int64_t(job)).bind(2, int64_t(phase));
  s.step();
  const int64_t n = s.columnInt(0);
  s.reset();
  return n;
}

bool JobStore::hasRemainingWork(uint64_t job, int phase) {
  if (!remainingValid_) loadRemainingWork();
  return remaining_.any(job, phase);
}

int64_t JobStore::openLeaseCount(uint64_t job) {
  auto& s = db_.prepare("SELECT COUNT(*) FROM leases WHERE job = ?");
  s.bind(1, int64_t(job));
  s.step();
  const int64_t n = s.columnInt(0);
  s.reset();
  return n;
}

std::map<uint32_t, int64_t> JobStore::pendingWorkByCell(uint64_t job, int phase, size_t limit) {
  if (!remainingValid_) loadRemainingWork();
  std::map<uint32_t, int64_t> result;
  if (limit == 0) return result;
  remaining_.visitRanked(job, phase, [&](uint32_t cell, int64_t work) {
    result[cell] = work;
    return result.size() < limit;
  });
  return result;
}

void JobStore::dropJobWork(uint64_t job) {
  unleasedValid_ = remainingValid_ = false;
  auto& del = db_.prepare("DELETE FROM batches WHERE job = ?");
  del.bind(1, int64_t(job));
  del.run();
  auto& close = db_.prepare("DELETE FROM leases WHERE job = ?");
  close.bind(1, int64_t(job));
  close.run();
}

void JobStore::restartJob(uint64_t job, int64_t nowMs) {
  jobsChanged();
  dropJobWork(job);
  for (const char* table : {"photons", "film", "render_progress", "render_passes", "lease_log"}) {
    auto& s = db_.prepare(fmt::format("DELETE FROM {} WHERE job = ?", table));
    s.bind(1, int64_t(job));
    s.run();
  }
  counters_.dropAllBut(job, kPhotonPassRestarts);
  addCounter(job, kPhotonPassRestarts, 1);
  auto& records = db_.prepare(
      "UPDATE jobs SET photon_record_bytes = ?, photon_source = 0, photons_complete = 0 WHERE id = ?");
  records.bind(1, int64_t(sizeof(PhotonRecord))).bind(2, int64_t(job));
  records.run();
  setJobState(job, JobState::Photons, nowMs);
  photons_.forget({job, 0});
}

void JobStore::addCounter(uint64_t job, std::string_view name, int64_t delta) { counters_.add(job, name, delta); }

JobStore::JobFileBytes JobStore::jobFileBytes(uint64_t job) const {
  namespace fs = std::filesystem;
  JobFileBytes bytes;
  std::error_code error;
  const auto size = [&](const fs::path& path) {
    const auto n = fs::file_size(path, error);
    return error ? int64_t(0) : int64_t(n);
  };
  struct stat photonFile {};
  if (::stat(photons_.pathOf({job, 0}).c_str(), &photonFile) == 0)
    bytes.photons = std::min<int64_t>(int64_t(photonFile.st_size), int64_t(photonFile.st_blocks) * 512);
  for (const AppendFiles::Key& key : batches_.filesOnDisk())
    if (key.first == job) bytes.batches += size(batches_.pathOf(key));
  return bytes;
}

int64_t JobStore::databaseBytes() const {
  std::error_code error;
  int64_t total = 0;
  for (const char* suffix : {"", "-wal"}) {
    const auto n = std::filesystem::file_size(db_.path() + std::string(suffix), error);
    if (!error) total += int64_t(n);
  }
  return total;
}

void JobStore::raiseCounter(uint64_t job, std::string_view name, int64_t value) { counters_.raise(job, name, value); }

void JobStore::logLease(const LeaseLogEntry& e) {
  auto& s = db_.prepare(
      "INSERT INTO lease_log(job, lease, phase, cell, more_cells, work, worker, sent_ms, result_ms, lease_us, "
      "load_us, cells_loaded, triangles_loaded, cpu_us, run_queue_us, more_cell_work) VALUES (?, ?, ?, ?, ?, ?, ?, ?, "
      "?, ?, ?, ?, ?, ?, ?, ?)");
  s.bind(1, int64_t(e.job)).bind(2, int64_t(e.lease)).bind(3, int64_t(e.phase)).bind(4, int64_t(e.cell));
  s.bind(5, int64_t(e.moreCells)).bind(6, e.work).bind(7, e.worker).bind(8, e.sentMs).bind(9, e.resultMs);
  s.bind(10, e.leaseMicros).bind(11, e.loadMicros).bind(12, e.cellsLoaded).bind(13, e.trianglesLoaded);
  // Unrecorded (-1) as NULL, as the rows of schema 8 have them.
  if (e.cpuMicros >= 0) s.bind(14, e.cpuMicros);
  else s.bindNull(14);
  if (e.runQueueMicros >= 0) s.bind(15, e.runQueueMicros);
  else s.bindNull(15);
  if (e.moreCellsLogged) s.bind(16, moreCellWorkText(e.moreCellWork));
  else s.bindNull(16);
  s.run();
}

std::vector<LeaseLogEntry> JobStore::leaseLog(uint64_t job) {
  auto& s = db_.prepare(
      "SELECT lease, phase, cell, more_cells, work, worker, sent_ms, result_ms, lease_us, load_us, cells_loaded, "
      "triangles_loaded, IFNULL(cpu_us, -1), IFNULL(run_queue_us, -1), more_cell_work IS NOT NULL, "
      "IFNULL(more_cell_work, '') FROM lease_log WHERE job = ? "
      "ORDER BY result_ms, lease");
  s.bind(1, int64_t(job));
  std::vector<LeaseLogEntry> log;
  while (s.step()) {
    LeaseLogEntry e;
    e.job = job;
    e.lease = uint64_t(s.columnInt(0));
    e.phase = int(s.columnInt(1));
    e.cell = uint32_t(s.columnInt(2));
    e.moreCells = uint32_t(s.columnInt(3));
    e.work = s.columnInt(4);
    e.worker = s.columnText(5);
    e.sentMs = s.columnInt(6);
    e.resultMs = s.columnInt(7);
    e.leaseMicros = s.columnInt(8);
    e.loadMicros = s.columnInt(9);
    e.cellsLoaded = s.columnInt(10);
    e.trianglesLoaded = s.columnInt(11);
    e.cpuMicros = s.columnInt(12);
    e.runQueueMicros = s.columnInt(13);
    e.moreCellsLogged = s.columnInt(14) != 0;
    e.moreCellWork = moreCellWorkOf(s.columnText(15));
    log.push_back(std::move(e));
  }
  s.reset();
  return log;
}

std::map<std::string, int64_t> JobStore::counters(uint64_t job) {
  const CounterTable::Values& values = counters_.of(job);
  return {values.begin(), values.end()};
}

void JobStore::addPhotons(uint64_t job, uint32_t cell, int64_t count, std::string_view payload) {
  recordPhotons(job, cell, count, photons_.append({job, 0}, payload));
}

void JobStore::addPhotonsAt(uint64_t job, uint32_t cell, const FileExtent& extent) {
  recordPhotons(job, cell, extent.size / int64_t(sizeof(PhotonRecord)), extent);
}

void JobStore::recordPhotons(uint64_t job, uint32_t cell, int64_t count, const FileExtent& extent) {
  auto& s = db_.prepare(
      "INSERT INTO photons(job, cell, count, payload, file_offset, file_size, file_crc) VALUES (?, ?, ?, x'', ?, ?, ?)");
  s.bind(1, int64_t(job)).bind(2, int64_t(cell)).bind(3, count).bind(4, extent.offset).bind(5, extent.size);
  s.bind(6, int64_t(extent.crc));
  s.run();
}

int64_t JobStore::reserveDepositRegion(uint64_t job, int64_t size, std::string_view head) {
  const int64_t offset = photons_.reserve({job, 0}, size, head);
  auto& s = db_.prepare("UPDATE jobs SET photon_region_end = MAX(photon_region_end, ?) WHERE id = ?");
  s.bind(1, offset + size).bind(2, int64_t(job));
  s.run();
  return offset;
}

std::vector<std::string> JobStore::photonBatches(uint64_t job, uint32_t cell) {
  // Where each batch lies first (rows of schema version 2 and older hold it
  // as a blob), then the reads, so that a damaged file leaves no statement open.
  struct Stored {
    std::optional<std::string> blob;
    FileExtent extent;
  };
  std::vector<Stored> stored;
  auto& s = db_.prepare(
      "SELECT file_offset IS NULL, payload, file_offset, file_size, file_crc FROM photons "
      "WHERE job = ? AND cell = ? ORDER BY id");
  s.bind(1, int64_t(job)).bind(2, int64_t(cell));
  while (s.step()) {
    Stored batch;
    if (s.columnInt(0) != 0) {
      auto blob = s.columnBlob(1);
      batch.blob.emplace(reinterpret_cast<const char*>(blob.data()), blob.size());
    } else {
      batch.extent = {s.columnInt(2), s.columnInt(3), uint32_t(s.columnInt(4))};
    }
    stored.push_back(std::move(batch));
  }
  s.reset();
  std::vector<std::string> result;
  result.reserve(stored.size());
  for (Stored& batch : stored)
    result.push_back(batch.blob ? std::move(*batch.blob) : photons_.read({job, 0}, batch.extent));
  return result;
}

std::optional<std::vector<FileExtent>> JobStore::photonExtents(uint64_t job, uint32_t cell) {
  auto& s = db_.prepare(
      "SELECT file_offset IS NULL, file_offset, file_size, file_crc FROM photons WHERE job = ? AND cell = ? "
      "ORDER BY id");
  s.bind(1, int64_t(job)).bind(2, int64_t(cell));
  std::optional<std::vector<FileExtent>> extents(std::in_place);
  while (s.step()) {
    if (s.columnInt(0) != 0) {
      extents.reset();
      break;
    }
    extents->push_back({s.columnInt(1), s.columnInt(2), uint32_t(s.columnInt(3))});
  }
  s.reset();
  return extents;
}

void JobStore::addFilm(uint64_t job, const std::unordered_map<uint32_t, FixedRgb>& sums, uint64_t pixelCount) {
  // Group by chunk, then read-modify-write each chunk once.
  std::map<uint32_t, std::vector<std::pair<uint32_t, FixedRgb>>> byChunk;
  for (const auto& [pixel, rgb] : sums) {
    if (pixel >= pixelCount) throw std::runtime_error(fmt::format("film: pixel {} outside the image", pixel));
    byChunk[pixel / kFilmChunkPixels].push_back({pixel % kFilmChunkPixels, rgb});
  }
  auto& read = db_.prepare("SELECT payload FROM film WHERE job = ? AND chunk = ?");
  auto& write = db_.prepare("INSERT OR REPLACE INTO film(job, chunk, payload) VALUES (?, ?, ?)");
  std::vector<FixedRgb> chunk(kFilmChunkPixels);
  for (const auto& [index, entries] : byChunk) {
    std::fill(chunk.begin(), chunk.end(), FixedRgb{});
    read.bind(1, int64_t(job)).bind(2, int64_t(index));
    if (read.step()) {
      auto blob = read.columnBlob(0);
      std::memcpy(chunk.data(), blob.data(), std::min(blob.size(), chunk.size() * sizeof(FixedRgb)));
    }
    read.reset();
    for (const auto& [offset, rgb] : entries)
      if (!chunk[offset].addWithinRange(rgb)) throw FilmRangeError();
    write.bind(1, int64_t(job)).bind(2, int64_t(index)).bindBlob(3, chunk.data(), chunk.size() * sizeof(FixedRgb));
    write.run();
  }
}

void JobStore::setJobSensors(uint64_t job, std::string_view records) {
  auto& s = db_.prepare("INSERT OR REPLACE INTO job_sensors(job, records) VALUES (?, ?)");
  s.bind(1, int64_t(job)).bindBlob(2, records.data(), records.size());
  s.run();
}

std::string JobStore::jobSensors(uint64_t job) {
  auto& s = db_.prepare("SELECT records FROM job_sensors WHERE job = ?");
  s.bind(1, int64_t(job));
  std::string records;
  if (s.step()) {
    const auto blob = s.columnBlob(0);
    records.assign(reinterpret_cast<const char*>(blob.data()), blob.size());
  }
  s.reset();
  return records;
}

std::vector<FixedRgb> JobStore::film(uint64_t job, uint64_t pixelCount) {
  std::vector<FixedRgb> result(pixelCount);
  auto& s = db_.prepare("SELECT chunk, payload FROM film WHERE job = ?");
  s.bind(1, int64_t(job));
  while (s.step()) {
    const uint64_t first = uint64_t(s.columnInt(0)) * kFilmChunkPixels;
    auto blob = s.columnBlob(1);
    const size_t pixels = std::min<size_t>(blob.size() / sizeof(FixedRgb), pixelCount > first ? pixelCount - first : 0);
    std::memcpy(result.data() + first, blob.data(), pixels * sizeof(FixedRgb));
  }
  s.reset();
  return result;
}

void JobStore::reclaimBatchFiles() {
  if (reclaimCandidates_.empty()) return;
  auto& used = db_.prepare("SELECT EXISTS (SELECT 1 FROM batches WHERE job = ? AND file_segment = ?)");
  for (auto it = reclaimCandidates_.begin(); it != reclaimCandidates_.end();) {
    const auto& [job, segment] = *it;
    const auto current = batchSegments_.find(job);
    if (current != batchSegments_.end() && current->second == segment) {
      it = reclaimCandidates_.erase(it);   // written to again (a rollback revived the job)
      continue;
    }
    used.bind(1, int64_t(job)).bind(2, int64_t(segment));
    const bool referenced = used.step() && used.columnInt(0) != 0;
    used.reset();
    if (referenced) {
      ++it;
    } else {
      batches_.remove(*it);
      it = reclaimCandidates_.erase(it);
    }
  }
}

}  // namespace portico
