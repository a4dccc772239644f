#include "coordinator/job_store.h"

#include <fmt/format.h>

#include <sqlite3.h>

#include <algorithm>
#include <cstring>
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

JobStore::JobStore(const std::string& path)
    : db_(path, sql::Database::Mode::ReadWriteCreate),
      photons_(path + "-photons", [this](uint64_t job) {
        auto& s = db_.prepare("SELECT COALESCE(MAX(file_offset + file_size), 0) FROM photons WHERE job = ?");
        s.bind(1, int64_t(job));
        const int64_t end = s.step() ? s.columnInt(0) : 0;
        s.reset();
        return end;
      }) {
  db_.exec("PRAGMA journal_mode = WAL");
  // NORMAL is durable across process crashes in WAL mode (only an OS crash
  // can lose the last commits), which is the failure portico guards against.
  db_.exec("PRAGMA synchronous = NORMAL");
  db_.exec("PRAGMA foreign_keys = ON");
  migrate();
  sqlite3_rollback_hook(
      db_.handle(), [](void* store) { static_cast<JobStore*>(store)->unleasedValid_ = false; }, this);
  // The hook misses a nested transaction's partial rollback (a savepoint).
  db_.setRollbackListener([this] { unleasedValid_ = false; });
}

void JobStore::loadUnleasedWork() {
  unleased_.clear();
  auto& s = db_.prepare(
      "SELECT job, phase, cell, SUM(work), COUNT(*) FROM batches WHERE lease IS NULL GROUP BY job, phase, cell");
  while (s.step())
    unleased_[{uint64_t(s.columnInt(0)), int(s.columnInt(1)), uint32_t(s.columnInt(2))}] = {s.columnInt(3),
                                                                                             s.columnInt(4)};
  s.reset();
  unleasedValid_ = true;
}

void JobStore::migrate() {
  const int version = db_.userVersion();
  if (version > kSchemaVersion)
    throw std::runtime_error(fmt::format("{}: schema version {} is newer than this coordinator ({}); upgrade portico",
                                         db_.path(), version, kSchemaVersion));
  // Steps fall through: a database at version v runs steps v+1..latest,
  // each in its own transaction.
  if (version < 1) {
    sql::Transaction tx(db_);
    db_.exec(R"sql(
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
    )sql");
    db_.setUserVersion(1);
    tx.commit();
  }
  if (version < 2) {
    // Attempt numbers: how many lost leases each queued batch has been in.
    sql::Transaction tx(db_);
    db_.exec("ALTER TABLE batches ADD COLUMN attempts INTEGER NOT NULL DEFAULT 0");
    db_.setUserVersion(2);
    tx.commit();
  }
  if (version < 3) {
    // Photon payloads move to append-only files (photon_files.h); rows keep
    // where each lies. Rows written before keep their blob (file_offset NULL).
    sql::Transaction tx(db_);
    db_.exec(R"sql(
      ALTER TABLE photons ADD COLUMN file_offset INTEGER;
      ALTER TABLE photons ADD COLUMN file_size INTEGER NOT NULL DEFAULT 0;
      ALTER TABLE photons ADD COLUMN file_crc INTEGER NOT NULL DEFAULT 0;
    )sql");
    db_.setUserVersion(3);
    tx.commit();
  }
}

uint64_t JobStore::createJob(const std::string& spec, int64_t nowMs) {
  auto& s = db_.prepare("INSERT INTO jobs(spec, state, created_ms, phase_started_ms) VALUES (?, ?, ?, ?)");
  s.bindBlob(1, spec.data(), spec.size()).bind(2, toString(JobState::Photons)).bind(3, nowMs).bind(4, nowMs);
  s.run();
  return static_cast<uint64_t>(db_.lastInsertRowId());
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
  return job;
}
constexpr const char* kJobColumns = "id, state, error, spec, created_ms, phase_started_ms, finished_ms";
}  // namespace

std::optional<JobRecord> JobStore::job(uint64_t id) {
  auto& s = db_.prepare(fmt::format("SELECT {} FROM jobs WHERE id = ?", kJobColumns));
  s.bind(1, int64_t(id));
  std::optional<JobRecord> result;
  if (s.step()) result = readJob(s);
  s.reset();
  return result;
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
  const bool finished = !isActive(state);
  auto& s = db_.prepare(
      "UPDATE jobs SET state = ?, error = ?, phase_started_ms = ?, finished_ms = ? WHERE id = ?");
  s.bind(1, toString(state)).bind(2, error).bind(3, nowMs).bind(4, finished ? nowMs : int64_t(0)).bind(5, int64_t(job));
  s.run();
}

void JobStore::addBatch(uint64_t job, uint32_t cell, int phase, BatchKind kind, int64_t work,
                        std::string_view payload) {
  auto& s = db_.prepare("INSERT INTO batches(job, cell, phase, kind, work, payload) VALUES (?, ?, ?, ?, ?, ?)");
  s.bind(1, int64_t(job)).bind(2, int64_t(cell)).bind(3, int64_t(phase)).bind(4, int64_t(kind)).bind(5, work);
  s.bindBlob(6, payload.data(), payload.size());
  s.run();
  if (unleasedValid_) {
    Unleased& entry = unleased_[{job, phase, cell}];
    entry.work += work;
    entry.batches += 1;
  }
}

int64_t JobStore::queuedRays(uint64_t job, int phase) {
  auto& s = db_.prepare("SELECT COALESCE(SUM(work), 0) FROM batches WHERE job = ? AND phase = ? AND kind = 0");
  s.bind(1, int64_t(job)).bind(2, int64_t(phase));
  s.step();
  const int64_t n = s.columnInt(0);
  s.reset();
  return n;
}

std::vector<PendingCell> JobStore::pendingCells(size_t limit) {
  if (!unleasedValid_) loadUnleasedWork();
  std::map<uint64_t, int> activePhase;
  auto& s = db_.prepare("SELECT id, state FROM jobs WHERE state IN ('photons', 'render')");
  while (s.step()) activePhase[uint64_t(s.columnInt(0))] = phaseOf(jobStateFromString(s.columnText(1)));
  s.reset();
  std::vector<PendingCell> result;
  for (const auto& [key, entry] : unleased_) {
    const auto& [job, phase, cell] = key;
    const auto active = activePhase.find(job);
    if (active != activePhase.end() && active->second == phase) result.push_back({job, cell, phase, entry.work});
  }
  // Oldest job first; in it, most work first (ties: lower cell).
  std::sort(result.begin(), result.end(), [](const PendingCell& a, const PendingCell& b) {
    return std::tie(a.job, b.work, a.cell) < std::tie(b.job, a.work, b.cell);
  });
  if (result.size() > limit) result.resize(limit);
  return result;
}

// The cell's unleased batches, oldest first, up to maxWork (at least one).
// Returns their work; `attempt` is one more than the most attempts any had.
int64_t JobStore::takeUnleased(const PendingCell& cell, int64_t maxWork, std::vector<QueuedBatch>& batches,
                               uint32_t& attempt) {
  auto& select = db_.prepare(
      "SELECT id, work, payload, attempts FROM batches WHERE job = ? AND phase = ? AND cell = ? AND lease IS NULL "
      "ORDER BY id");
  select.bind(1, int64_t(cell.job)).bind(2, int64_t(cell.phase)).bind(3, int64_t(cell.cell));
  int64_t total = 0;
  while (select.step()) {
    const int64_t work = select.columnInt(1);
    if (!batches.empty() && total + work > maxWork) break;
    auto blob = select.columnBlob(2);
    const uint32_t attempts = uint32_t(select.columnInt(3));
    batches.push_back(
        {select.columnInt(0), work, std::string(reinterpret_cast<const char*>(blob.data()), blob.size()), attempts});
    attempt = std::max(attempt, attempts + 1);
    total += work;
  }
  select.reset();
  return total;
}

// Marks the batches as the lease's, and takes them out of the cell's unleased work.
void JobStore::markLeased(uint64_t lease, const PendingCell& cell, const std::vector<QueuedBatch>& batches,
                          int64_t work) {
  auto& mark = db_.prepare("UPDATE batches SET lease = ? WHERE id = ?");
  for (const QueuedBatch& batch : batches) {
    mark.bind(1, int64_t(lease)).bind(2, batch.id);
    mark.run();
  }
  if (unleasedValid_) {
    const auto key = std::make_tuple(cell.job, cell.phase, cell.cell);
    Unleased& entry = unleased_[key];
    entry.work -= work;
    entry.batches -= int64_t(batches.size());
    if (entry.batches <= 0) unleased_.erase(key);
  }
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
  return {lease, cell.job, cell.cell, cell.phase, worker, attempt, "open"};
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
          s.columnText(4), uint32_t(s.columnInt(5)), s.columnText(6)};
}
}  // namespace

std::optional<LeaseRecord> JobStore::lease(uint64_t id) {
  auto& s = db_.prepare("SELECT id, job, cell, phase, worker, attempt, state FROM leases WHERE id = ?");
  s.bind(1, int64_t(id));
  std::optional<LeaseRecord> result;
  if (s.step()) result = readLease(s);
  s.reset();
  return result;
}

std::vector<LeaseRecord> JobStore::openLeasesOf(const std::string& worker) {
  auto& s = db_.prepare(
      "SELECT id, job, cell, phase, worker, attempt, state FROM leases WHERE state = 'open' AND worker = ?");
  s.bind(1, worker);
  std::vector<LeaseRecord> result;
  while (s.step()) result.push_back(readLease(s));
  s.reset();
  return result;
}

std::vector<LeaseRecord> JobStore::openLeases() {
  auto& s = db_.prepare("SELECT id, job, cell, phase, worker, attempt, state FROM leases WHERE state = 'open'");
  std::vector<LeaseRecord> result;
  while (s.step()) result.push_back(readLease(s));
  s.reset();
  return result;
}

void JobStore::completeLease(uint64_t lease) {
  auto& del = db_.prepare("DELETE FROM batches WHERE lease = ?");
  del.bind(1, int64_t(lease));
  del.run();
  auto& close = db_.prepare("UPDATE leases SET state = 'done' WHERE id = ?");
  close.bind(1, int64_t(lease));
  close.run();
}

void JobStore::requeueLease(uint64_t lease, bool lost) {
  unleasedValid_ = false;   // rare: recount at the next pendingCells()
  auto& release = db_.prepare("UPDATE batches SET lease = NULL, attempts = attempts + ? WHERE lease = ?");
  release.bind(1, int64_t(lost ? 1 : 0)).bind(2, int64_t(lease));
  release.run();
  auto& close = db_.prepare("UPDATE leases SET state = 'requeued' WHERE id = ? AND state = 'open'");
  close.bind(1, int64_t(lease));
  close.run();
}

int JobStore::requeueAllOpenLeases() {
  unleasedValid_ = false;
  sql::Transaction tx(db_);
  db_.exec("UPDATE batches SET lease = NULL WHERE lease IN (SELECT id FROM leases WHERE state = 'open')");
  db_.exec("UPDATE leases SET state = 'requeued' WHERE state = 'open'");
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

int64_t JobStore::openLeaseCount(uint64_t job) {
  auto& s = db_.prepare("SELECT COUNT(*) FROM leases WHERE job = ? AND state = 'open'");
  s.bind(1, int64_t(job));
  s.step();
  const int64_t n = s.columnInt(0);
  s.reset();
  return n;
}

std::map<uint32_t, int64_t> JobStore::pendingWorkByCell(uint64_t job, int phase, size_t limit) {
  auto& s = db_.prepare(
      "SELECT cell, SUM(work) AS w FROM batches WHERE job = ? AND phase = ? GROUP BY cell ORDER BY w DESC LIMIT ?");
  s.bind(1, int64_t(job)).bind(2, int64_t(phase)).bind(3, int64_t(limit));
  std::map<uint32_t, int64_t> result;
  while (s.step()) result[uint32_t(s.columnInt(0))] = s.columnInt(1);
  s.reset();
  return result;
}

void JobStore::dropJobWork(uint64_t job) {
  unleasedValid_ = false;
  auto& del = db_.prepare("DELETE FROM batches WHERE job = ?");
  del.bind(1, int64_t(job));
  del.run();
  auto& close = db_.prepare("UPDATE leases SET state = 'requeued' WHERE job = ? AND state = 'open'");
  close.bind(1, int64_t(job));
  close.run();
}

void JobStore::restartJob(uint64_t job, int64_t nowMs) {
  dropJobWork(job);
  for (const char* table : {"photons", "film"}) {
    auto& s = db_.prepare(fmt::format("DELETE FROM {} WHERE job = ?", table));
    s.bind(1, int64_t(job));
    s.run();
  }
  auto& counters = db_.prepare("DELETE FROM counters WHERE job = ? AND name != ?");
  counters.bind(1, int64_t(job)).bind(2, kPhotonPassRestarts);
  counters.run();
  addCounter(job, kPhotonPassRestarts, 1);
  setJobState(job, JobState::Photons, nowMs);
  photons_.forget(job);
}

void JobStore::addCounter(uint64_t job, std::string_view name, int64_t delta) {
  auto& s = db_.prepare(
      "INSERT INTO counters(job, name, value) VALUES (?, ?, ?) "
      "ON CONFLICT(job, name) DO UPDATE SET value = value + excluded.value");
  s.bind(1, int64_t(job)).bind(2, name).bind(3, delta);
  s.run();
}

std::map<std::string, int64_t> JobStore::counters(uint64_t job) {
  auto& s = db_.prepare("SELECT name, value FROM counters WHERE job = ?");
  s.bind(1, int64_t(job));
  std::map<std::string, int64_t> result;
  while (s.step()) result[s.columnText(0)] = s.columnInt(1);
  s.reset();
  return result;
}

void JobStore::addPhotons(uint64_t job, uint32_t cell, int64_t count, std::string_view payload) {
  const PhotonExtent extent = photons_.append(job, payload);
  auto& s = db_.prepare(
      "INSERT INTO photons(job, cell, count, payload, file_offset, file_size, file_crc) VALUES (?, ?, ?, x'', ?, ?, ?)");
  s.bind(1, int64_t(job)).bind(2, int64_t(cell)).bind(3, count).bind(4, extent.offset).bind(5, extent.size);
  s.bind(6, int64_t(extent.crc));
  s.run();
}

std::vector<std::string> JobStore::photonBatches(uint64_t job, uint32_t cell) {
  // Where each batch lies first (rows of schema version 2 and older hold it
  // as a blob), then the reads, so that a damaged file leaves no statement open.
  struct Stored {
    std::optional<std::string> blob;
    PhotonExtent extent;
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
    result.push_back(batch.blob ? std::move(*batch.blob) : photons_.read(job, batch.extent));
  return result;
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
    for (const auto& [offset, rgb] : entries) chunk[offset] += rgb;
    write.bind(1, int64_t(job)).bind(2, int64_t(index)).bindBlob(3, chunk.data(), chunk.size() * sizeof(FixedRgb));
    write.run();
  }
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

}  // namespace portico
