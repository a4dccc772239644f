// A photon lease's deposits written into its deposit region of the job's
// photon file, when this worker shares the coordinator's file system
// (proto/wire.capnp DepositRegion; the reasoning, and what the coordinator
// checks, in coordinator/deposit_regions.h).
//
// The region's head must name this job and lease (deposit_region_head.h):
// a file of the same name on another machine, or of another coordinator,
// does not, and the deposits then go in the Result. Every cell's records
// that fit go out in one write, from one aligned buffer, with O_DIRECT where
// the file system takes it (each page of the pass's hundreds of megabytes
// would otherwise be page cache the machine hands out anew: the reason the
// coordinator writes its own batches so, coordinator/append_files.h; on the
// octagon's pass, through the page cache the workers' system time was
// 0.6 s higher and the pass 5 % slower). The write runs on a thread of its
// own and the Result leaves once it is done (finish).
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "common/transport/deposit_region_head.h"
#include "common/transport/photon_record.h"
#include "proto/wire.capnp.h"

namespace portico {

class DepositRegionWriter {
 public:
  struct Extent {
    uint64_t offset = 0, size = 0;
    uint32_t crc = 0;
  };
  struct Written {
    deposit_region::Nonce nonce{};
    // Per cell of the deposits, in their order: where its records go, or
    // nothing when they did not fit (they go in the Result).
    std::vector<std::optional<Extent>> extents;
  };

  DepositRegionWriter() = default;
  ~DepositRegionWriter();
  DepositRegionWriter(const DepositRegionWriter&) = delete;
  DepositRegionWriter& operator=(const DepositRegionWriter&) = delete;

  // Lays the lease's deposits out in its region and starts writing them on
  // the writer's own thread, so that the tracing thread goes on with the
  // next lease while the disk takes them (a direct write waits for the
  // device). Nothing when the region cannot be used: its file does not open
  // here, its head is not this lease's, or an earlier write to it failed
  // (each logged once per file).
  std::optional<Written> write(wire::DepositRegion::Reader region, uint64_t job, uint64_t lease,
                               const std::map<uint32_t, std::vector<PhotonRecord>>& deposits);
  // The records of a write that failed, for the Result instead: the bytes
  // that were to be written from file offset `firstOffset` on.
  struct Unwritten {
    uint64_t firstOffset = 0;
    std::string bytes;
  };
  // Waits until the lease's write (if it has one) is on disk: true, or
  // false with `error` when it failed (a full disk, a failing one), and
  // then its records in `unwritten`, to send in the Result
  // (sendDepositsInResult). Call before sending the lease's Result, once
  // per lease that was traced.
  bool finish(uint64_t lease, std::string& error, Unwritten* unwritten = nullptr);

 private:
  struct OpenFile {
    int descriptor = -1;   // read and write, through the page cache
    int direct = -1;       // O_DIRECT, or -1 where the file system refuses it
    bool failed = false;   // a write failed: the leases after it send their deposits
  };
  struct PendingWrite {
    std::string path;
    std::shared_ptr<OpenFile> file;
    char* buffer = nullptr;
    size_t used = 0;    // bytes of records
    size_t bytes = 0;   // written: used, padded to whole blocks
    uint64_t offset = 0;
    bool done = false;
    std::string error;   // when it failed
  };
  using Buffer = std::unique_ptr<char, void (*)(void*)>;

  std::shared_ptr<OpenFile> open(const std::string& path, bool again);
  static std::optional<deposit_region::Nonce> readHead(const OpenFile& file, uint64_t offset, uint64_t job,
                                                       uint64_t lease);
  static std::string writeAll(OpenFile& file, const char* data, size_t size, uint64_t offset);
  Buffer takeBuffer(size_t bytes);
  void recycle(PendingWrite& pending);
  void writerLoop();
  void warnOnce(const std::string& path, const std::string& message, bool warning);

  std::mutex mutex_;   // everything below
  std::condition_variable changed_;
  std::map<std::string, std::shared_ptr<OpenFile>> files_;
  std::set<std::string> warned_;
  std::deque<std::pair<uint64_t, std::shared_ptr<PendingWrite>>> queue_;
  std::map<uint64_t, std::shared_ptr<PendingWrite>> pending_;
  std::map<const PendingWrite*, Buffer> buffers_;   // each pending write's
  std::vector<std::pair<size_t, Buffer>> spareBuffers_;
  std::thread writer_;
  bool stopping_ = false;
};

// Puts a Result's deposits that were to be in its region back in the
// Result (records, no file extent, no nonce): after a write that failed.
void sendDepositsInResult(wire::Result::Builder result, const DepositRegionWriter::Unwritten& unwritten);

// The worker's writer, shared by its leases.
DepositRegionWriter& depositRegionWriter();

}  // namespace portico
