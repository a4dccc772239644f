#include "worker/deposit_region_writer.h"

#include <fcntl.h>
#include <unistd.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <new>
#include <stdexcept>

#include "common/util/crc32c.h"
#include "common/util/file_at.h"

namespace portico {

namespace {
constexpr size_t kBlock = size_t(deposit_region::kBlockBytes);
// Files of jobs this worker wrote to, kept open; more are closed first.
constexpr size_t kMostOpenFiles = 8;
// Written buffers kept for the next leases (a lease's is ~1-2 MB): fresh
// ones would be pages the kernel zeroes anew each time.
constexpr size_t kMostSpareBuffers = 4;
size_t roundUp(size_t bytes) { return (bytes + kBlock - 1) / kBlock * kBlock; }

void closeFile(int& descriptor) {
  if (descriptor >= 0) ::close(descriptor);
  descriptor = -1;
}
}  // namespace

DepositRegionWriter::~DepositRegionWriter() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  if (writer_.joinable()) writer_.join();
}

void DepositRegionWriter::warnOnce(const std::string& path, const std::string& message, bool warning) {
  if (!warned_.insert(path).second) return;
  if (warning)
    spdlog::warn("{}", message);
  else
    spdlog::info("{}", message);
}

// Under mutex_. A file is closed only when no pending write holds it (shared_ptr).
std::shared_ptr<DepositRegionWriter::OpenFile> DepositRegionWriter::open(const std::string& path, bool again) {
  auto it = files_.find(path);
  if (it != files_.end() && !again) return it->second;
  if (it != files_.end()) files_.erase(it);
  if (files_.size() >= kMostOpenFiles) files_.clear();
  // No O_CREAT: the coordinator made the file; one missing here is another machine's.
  const int descriptor = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
  if (descriptor < 0) {
    warnOnce(path, fmt::format("deposits go in the results: the job's photon file {} does not open here ({})", path,
                               std::strerror(errno)),
             false);
    return nullptr;
  }
  auto file = std::shared_ptr<OpenFile>(new OpenFile{descriptor, -1, false}, [](OpenFile* f) {
    closeFile(f->descriptor);
    closeFile(f->direct);
    delete f;
  });
  file->direct = ::open(path.c_str(), O_RDWR | O_CLOEXEC | O_DIRECT);
  files_[path] = file;
  return file;
}

std::optional<deposit_region::Nonce> DepositRegionWriter::readHead(const OpenFile& file, uint64_t offset,
                                                                   uint64_t job, uint64_t lease) {
  // Through the page cache, where the coordinator wrote it.
  char head[deposit_region::kHeadBytes];
  int error = 0;
  if (readAt(file.descriptor, head, sizeof head, int64_t(offset), error) != sizeof head) return std::nullopt;
  return deposit_region::nonceOf(std::string_view(head, sizeof head), job, lease);
}

// An empty string, or what went wrong.
std::string DepositRegionWriter::writeAll(OpenFile& file, const char* data, size_t size, uint64_t offset) {
  int code = 0;
  if (file.direct >= 0) {
    const size_t written = writeAt(file.direct, data, size, int64_t(offset), code);
    if (written == size) return {};
    if (written != 0 || code != EINVAL)
      return fmt::format("cannot write {} bytes at offset {} ({})", size, offset, std::strerror(code));
    closeFile(file.direct);   // direct transfers refused: the page cache from now on
  }
  if (writeAt(file.descriptor, data, size, int64_t(offset), code) == size) return {};
  return fmt::format("cannot write {} bytes at offset {} ({})", size, offset, std::strerror(code));
}

DepositRegionWriter::Buffer DepositRegionWriter::takeBuffer(size_t bytes) {
  for (auto it = spareBuffers_.begin(); it != spareBuffers_.end(); ++it)
    if (it->first >= bytes) {
      Buffer buffer = std::move(it->second);
      spareBuffers_.erase(it);
      return buffer;
    }
  size_t capacity = kBlock;
  while (capacity < bytes) capacity *= 2;
  void* memory = std::aligned_alloc(kBlock, capacity);
  if (!memory) throw std::bad_alloc();
  if (!spareBuffers_.empty()) spareBuffers_.erase(spareBuffers_.begin());   // too small: make room
  return Buffer(static_cast<char*>(memory), std::free);
}

std::optional<DepositRegionWriter::Written> DepositRegionWriter::write(
    wire::DepositRegion::Reader region, uint64_t job, uint64_t lease,
    const std::map<uint32_t, std::vector<PhotonRecord>>& deposits) {
  const std::string path = region.getPath();
  const uint64_t offset = region.getOffset(), size = region.getSize();
  if (path.empty() || offset % kBlock != 0 || size % kBlock != 0 || size <= kBlock) return std::nullopt;
  std::unique_lock lock(mutex_);

  // The head names this lease: the file is the coordinator's. A cached
  // descriptor may be of a file since replaced: opened again once.
  std::shared_ptr<OpenFile> file = open(path, false);
  if (!file) return std::nullopt;
  std::optional<deposit_region::Nonce> nonce = readHead(*file, offset, job, lease);
  if (!nonce) {
    file = open(path, true);
    if (file) nonce = readHead(*file, offset, job, lease);
  }
  if (!file || !nonce) {
    warnOnce(path, fmt::format("deposits go in the results: {} at offset {} is not lease {}'s deposit region", path,
                               offset, lease),
             false);
    return std::nullopt;
  }
  if (file->failed) return std::nullopt;

  // The cells that fit, their records back to back after the head, in one write.
  Written written;
  written.nonce = *nonce;
  const size_t room = size_t(size) - kBlock;
  size_t used = 0;
  for (const auto& [cell, records] : deposits) {
    const size_t bytes = records.size() * sizeof(PhotonRecord);
    if (bytes == 0 || used + bytes > room) {
      written.extents.emplace_back();
      continue;
    }
    written.extents.push_back(Extent{offset + kBlock + used, bytes, 0});
    used += bytes;
  }
  if (used == 0) return written;
  auto pending = std::make_shared<PendingWrite>();
  pending->path = path;
  pending->file = file;
  pending->used = used;
  pending->bytes = roundUp(used);
  pending->offset = offset + kBlock;
  Buffer buffer = takeBuffer(pending->bytes);
  pending->buffer = buffer.get();
  buffers_.emplace(pending.get(), std::move(buffer));
  lock.unlock();   // the copy and the checksums, outside the lock

  size_t at = 0, index = 0;
  for (const auto& [cell, records] : deposits) {
    std::optional<Extent>& extent = written.extents[index++];
    if (!extent) continue;
    std::memcpy(pending->buffer + at, records.data(), size_t(extent->size));
    extent->crc = crc32c(pending->buffer + at, size_t(extent->size));
    at += size_t(extent->size);
  }
  std::memset(pending->buffer + used, 0, pending->bytes - used);

  lock.lock();
  if (!writer_.joinable()) writer_ = std::thread([this] { writerLoop(); });
  pending_[lease] = pending;
  queue_.emplace_back(lease, pending);
  lock.unlock();
  changed_.notify_all();
  return written;
}

void DepositRegionWriter::writerLoop() {
  std::unique_lock lock(mutex_);
  for (;;) {
    changed_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
    if (queue_.empty()) return;   // stopping, nothing left
    std::shared_ptr<PendingWrite> pending = queue_.front().second;
    queue_.pop_front();
    const bool failedBefore = pending->file->failed;
    lock.unlock();
    std::string error = failedBefore ? "an earlier write to the file failed"
                                     : writeAll(*pending->file, pending->buffer, pending->bytes, pending->offset);
    lock.lock();
    if (!error.empty()) {
      pending->file->failed = true;
      pending->error = fmt::format("{}: {}", pending->path, error);
      warnOnce(pending->path, "deposits go in the results from now on: " + pending->error, true);
    }
    pending->done = true;
    if (error.empty()) recycle(*pending);   // a failed write's records stay for finish
    changed_.notify_all();
  }
}

// Under mutex_: the write's buffer back to the spares (or freed).
void DepositRegionWriter::recycle(PendingWrite& pending) {
  if (auto it = buffers_.find(&pending); it != buffers_.end()) {
    if (spareBuffers_.size() < kMostSpareBuffers) spareBuffers_.emplace_back(roundUp(pending.bytes), std::move(it->second));
    buffers_.erase(it);
  }
  pending.buffer = nullptr;
}

bool DepositRegionWriter::finish(uint64_t lease, std::string& error, Unwritten* unwritten) {
  std::unique_lock lock(mutex_);
  auto it = pending_.find(lease);
  if (it == pending_.end()) return true;
  std::shared_ptr<PendingWrite> pending = it->second;
  pending_.erase(it);
  changed_.wait(lock, [&] { return pending->done; });
  error = pending->error;
  if (!error.empty() && unwritten && pending->buffer) {
    unwritten->firstOffset = pending->offset;
    unwritten->bytes.assign(pending->buffer, pending->used);
  }
  recycle(*pending);
  return error.empty();
}

void sendDepositsInResult(wire::Result::Builder result, const DepositRegionWriter::Unwritten& unwritten) {
  for (auto deposits : result.getDeposits()) {
    if (deposits.getFileSize() == 0) continue;
    const uint64_t at = deposits.getFileOffset() - unwritten.firstOffset, size = deposits.getFileSize();
    if (deposits.getFileOffset() < unwritten.firstOffset || at > unwritten.bytes.size() ||
        size > unwritten.bytes.size() - at)
      throw std::logic_error("a deposit extent outside its lease's failed write");
    deposits.setRecords(capnp::Data::Reader(reinterpret_cast<const kj::byte*>(unwritten.bytes.data() + at), size));
    deposits.setFileOffset(0);
    deposits.setFileSize(0);
    deposits.setFileCrc(0);
  }
  result.disownRegionNonce();
}

DepositRegionWriter& depositRegionWriter() {
  static DepositRegionWriter writer;
  return writer;
}

}  // namespace portico
