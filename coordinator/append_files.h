// What the coordinator stores by the megabyte, as append-only files beside
// jobs.db: the photons a job deposits (`jobs.db-photons/job-J.bin`) and the
// rays queued between cells (`jobs.db-batches/job-J-S.bin`, in segments).
// jobs.db keeps, in the same transaction as the rest of a Result, only where
// each batch lies (segment, offset, size, CRC-32C).
//
// Why not blobs in jobs.db: these bytes are most of what a photon pass moves
// (~70 MB of deposits and ~60 MB of crossing rays per million photons), and
// SQLite wrote each of them twice (the WAL, then the checkpoint into the
// database), freed their pages again when a lease consumed them, and read
// them back, all on the coordinator's one thread, which with two workers on
// two cores shares their cores (docs/pipeline-benchmark.md). Here each byte
// is written once.
//
// Crash safety. A batch is written before the transaction that records it
// commits. A coordinator killed in between leaves bytes no row refers to:
// the next coordinator starts each file at the end of its last recorded
// batch (truncating the rest) and writes over them. A Result whose
// transaction rolls back leaves a gap nobody reads. An operating-system
// crash can lose file pages that a committed row points to (SQLite's WAL
// and these files reach the disk independently): the CRC catches it on
// reading, and the read throws DamagedFileError naming the file, so a
// damaged batch is never used; the coordinator then runs the job's photon
// pass again (Coordinator::restartPhotonPass), which gives the same photons,
// bit for bit.
//
// Direct I/O (Caching::Direct, the photon files). A pass's deposits are
// hundreds of megabytes written once and read once, in the render phase.
// Through the page cache each of their pages is memory the machine hands
// out anew, and on a VM whose host backs guest memory lazily (and takes
// freed pages back) a page touched for the first time costs ~10x a reused
// one: on the 2-core development VM, dd of 375 MB (the octagon's deposits
// at 7.75 M photons) into a new file took 0.9-1.0 s of system time, on the
// cores the workers trace on, when the freed pages had gone back to the
// host, and 0.11 s with O_DIRECT in 1 MiB writes. So batches of
// kDirectLeastBytes or more (most of the bytes: a lease's deposits in its
// own cell) are written with O_DIRECT from a reused aligned buffer, each
// from a kDirectAlignment boundary, padded with zeros no row refers to,
// and read back with O_DIRECT from the device. A file system that refuses
// O_DIRECT (tmpfs on older kernels) gets page-cache I/O for that file. The
// queued rays keep the page cache: they are read back within seconds, and
// their consumed segments are deleted, so their pages are reused.
#pragma once

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace portico {

struct FileExtent {
  int64_t offset = 0;
  int64_t size = 0;
  uint32_t crc = 0;   // CRC-32C (common/util/crc32c.h)
};

// A file's bytes are not what its row says: lost, cut short, or changed.
struct DamagedFileError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A write the disk refused for now (full, over quota, failing): the caller
// retries later rather than blame what it was writing.
struct DiskWriteError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class AppendFiles {
 public:
  // A file: the job's, and which of its segments (always 0 when unsegmented).
  using Key = std::pair<uint64_t, uint32_t>;
  enum class Naming { PerJob, PerSegment };   // job-J.bin, job-J-S.bin
  enum class Caching { PageCache, Direct };
  static constexpr int64_t kDirectAlignment = 4096;
  // Smaller batches go through the page cache: a direct transfer costs a
  // device round trip, and a few kilobytes of new pages little.
  static constexpr int64_t kDirectLeastBytes = 64 << 10;

  // directory: created on first write. what: what a batch holds, for errors
  // ("photon batch"). committedEnd(key): the end of the file's last recorded
  // batch (0 when none), asked when the file is opened.
  AppendFiles(std::filesystem::path directory, Naming naming, std::string what,
              std::function<int64_t(Key)> committedEnd, Caching caching = Caching::PageCache);
  ~AppendFiles();
  AppendFiles(const AppendFiles&) = delete;
  AppendFiles& operator=(const AppendFiles&) = delete;

  // Writes the batch at the end of the file; throws DiskWriteError naming
  // the file when the disk is full or failing, std::runtime_error otherwise.
  FileExtent append(Key key, std::string_view bytes);
  // Sets `size` bytes (a multiple of kDirectAlignment) aside at the next
  // aligned offset, for another process to write (deposit regions,
  // coordinator/deposit_regions.h), writes `head` (at most one block,
  // padded with zeros) at their start, and returns their offset. Throws as
  // append does.
  int64_t reserve(Key key, int64_t size, std::string_view head);
  // The batch at `extent`; throws DamagedFileError naming the file when it
  // is missing, short, or fails its CRC.
  std::string read(Key key, const FileExtent& extent);
  // The bytes alone, unchecked (a migration checks them its own way).
  std::string readUnchecked(Key key, const FileExtent& extent);
  // The end of the file as this process writes it (0 when not open).
  int64_t end(Key key) const;

  std::filesystem::path pathOf(Key key) const;
  // Closes the file: the next use starts from its committed end again
  // (after its rows were deleted: from nothing).
  void forget(Key key);
  // Closes and deletes the file.
  void remove(Key key);
  // The files the directory holds (names this class did not write are ignored).
  std::vector<Key> filesOnDisk() const;

 private:
  struct OpenFile {
    int descriptor = -1;
    int directDescriptor = -1;   // O_DIRECT (Caching::Direct), or -1
    int64_t end = 0;             // where the next batch may start
  };
  OpenFile& open(Key key);
  void close(OpenFile& file);
  static void dropDirect(OpenFile& file);
  static bool goesDirect(const OpenFile& file, int64_t offset, int64_t size);
  // Reused, kDirectAlignment-aligned memory of at least `bytes` for direct I/O.
  char* staging(size_t bytes);
  // False when a direct transfer was refused before any byte (EINVAL).
  bool writeAll(Key key, int descriptor, const char* data, size_t size, int64_t offset);

  std::filesystem::path directory_;
  Naming naming_;
  std::string what_;
  std::function<int64_t(Key)> committedEnd_;
  Caching caching_;
  std::map<Key, OpenFile> files_;
  std::unique_ptr<char, void (*)(void*)> staging_{nullptr, std::free};
  size_t stagingBytes_ = 0;
};

}  // namespace portico
