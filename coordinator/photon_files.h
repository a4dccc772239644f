// The photons a job deposits, as append-only files beside jobs.db
// (`jobs.db-photons/job-N.bin`), one per job; jobs.db keeps, in the same
// transaction as the rest of a Result, only where each batch lies (offset,
// size, CRC-32).
//
// Why not blobs in jobs.db: the deposits are most of the bytes a photon pass
// moves (24 bytes each, ~2.7 a photon: ~130 MB at 2 M photons), and SQLite
// wrote each of them twice (the WAL, then the checkpoint into the database)
// and read it once more, on the coordinator's one thread, which with two
// workers on two cores shares their cores (docs/pipeline-benchmark.md).
// Here each byte is written once.
//
// Crash safety. A batch is written before the transaction that records it
// commits. A coordinator killed in between leaves bytes no row refers to:
// the next coordinator starts each job's file at the end of its last
// recorded batch (truncating the rest) and writes over them. A Result whose
// transaction rolls back leaves a gap nobody reads. An operating-system
// crash can lose file pages that a committed row points to (SQLite's WAL
// and these files reach the disk independently): the CRC catches it on
// reading, and the read fails naming the file, so a damaged batch is never
// used; the coordinator then runs the job's photon pass again
// (Coordinator::onFetchPhotons), which gives the same photons, bit for bit.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <string_view>

namespace portico {

struct PhotonExtent {
  int64_t offset = 0;
  int64_t size = 0;
  uint32_t crc = 0;
};

class PhotonFiles {
 public:
  // directory: created on first write. committedEnd(job): the end of the
  // job's last recorded batch (0 when none), asked once per job and run.
  PhotonFiles(std::filesystem::path directory, std::function<int64_t(uint64_t job)> committedEnd);
  ~PhotonFiles();
  PhotonFiles(const PhotonFiles&) = delete;
  PhotonFiles& operator=(const PhotonFiles&) = delete;

  // Writes the batch at the end of the job's file; throws std::runtime_error
  // naming the file when the write fails.
  PhotonExtent append(uint64_t job, std::string_view bytes);
  // The batch at `extent`; throws std::runtime_error naming the file when it
  // is missing, short, or fails its CRC.
  std::string read(uint64_t job, const PhotonExtent& extent);

  std::filesystem::path pathOf(uint64_t job) const;
  // Closes the job's file: the next use starts from its committed end again
  // (after the job's rows were deleted: from nothing).
  void forget(uint64_t job);

 private:
  struct OpenFile {
    int descriptor = -1;
    int64_t end = 0;
  };
  OpenFile& open(uint64_t job);

  std::filesystem::path directory_;
  std::function<int64_t(uint64_t)> committedEnd_;
  std::map<uint64_t, OpenFile> files_;
};

}  // namespace portico
