#include "coordinator/append_files.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cinttypes>
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <new>
#include <system_error>

#include <fmt/format.h>

#include "common/util/crc32c.h"
#include "common/util/file_at.h"

namespace portico {

namespace {
// Full, over quota, or failing: space or the device may come back.
[[noreturn]] void throwWriteError(int code, const std::string& what) {
  if (code == ENOSPC || code == EDQUOT || code == EIO) throw DiskWriteError(what);
  throw std::runtime_error(what);
}

int64_t alignDown(int64_t n) { return n / AppendFiles::kDirectAlignment * AppendFiles::kDirectAlignment; }
int64_t alignUp(int64_t n) { return alignDown(n + AppendFiles::kDirectAlignment - 1); }
}  // namespace

AppendFiles::AppendFiles(std::filesystem::path directory, Naming naming, std::string what,
                         std::function<int64_t(Key)> committedEnd, Caching caching)
    : directory_(std::move(directory)),
      naming_(naming),
      what_(std::move(what)),
      committedEnd_(std::move(committedEnd)),
      caching_(caching) {}

AppendFiles::~AppendFiles() {
  for (auto& [key, file] : files_) close(file);
}

std::filesystem::path AppendFiles::pathOf(Key key) const {
  return directory_ / (naming_ == Naming::PerJob ? fmt::format("job-{}.bin", key.first)
                                                 : fmt::format("job-{}-{}.bin", key.first, key.second));
}

std::vector<AppendFiles::Key> AppendFiles::filesOnDisk() const {
  std::vector<Key> keys;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(directory_, error)) {
    const std::string name = entry.path().filename().string();
    uint64_t job = 0;
    uint32_t segment = 0;
    int consumed = 0;
    const bool matches =
        naming_ == Naming::PerJob
            ? std::sscanf(name.c_str(), "job-%" SCNu64 ".bin%n", &job, &consumed) == 1
            : std::sscanf(name.c_str(), "job-%" SCNu64 "-%" SCNu32 ".bin%n", &job, &segment, &consumed) == 2;
    if (matches && size_t(consumed) == name.size() && pathOf({job, segment}).filename() == name)
      keys.emplace_back(job, segment);
  }
  return keys;
}

AppendFiles::OpenFile& AppendFiles::open(Key key) {
  if (auto it = files_.find(key); it != files_.end()) return it->second;
  std::error_code error;
  std::filesystem::create_directories(directory_, error);
  if (error)
    throwWriteError(error.value(), fmt::format("{}: cannot be created ({})", directory_.string(), error.message()));
  const std::string path = pathOf(key).string();
  const int descriptor = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (descriptor < 0) throwWriteError(errno, fmt::format("{}: cannot be opened ({})", path, std::strerror(errno)));
  // Bytes past the last recorded batch belong to Results that never
  // committed: drop them, and write from there.
  const int64_t end = committedEnd_(key);
  if (::ftruncate(descriptor, end) != 0) {
    const int code = errno;
    ::close(descriptor);
    throw std::runtime_error(fmt::format("{}: cannot be cut to {} bytes ({})", path, end, std::strerror(code)));
  }
  // -1 on a file system without O_DIRECT: the page cache then.
  const int direct = caching_ == Caching::Direct ? ::open(path.c_str(), O_RDWR | O_CLOEXEC | O_DIRECT) : -1;
  return files_[key] = OpenFile{descriptor, direct, end};
}

void AppendFiles::close(OpenFile& file) {
  ::close(file.descriptor);
  dropDirect(file);
}

char* AppendFiles::staging(size_t bytes) {
  if (bytes > stagingBytes_ || !staging_) {
    size_t capacity = size_t(kDirectAlignment);
    while (capacity < bytes) capacity *= 2;
    void* memory = std::aligned_alloc(size_t(kDirectAlignment), capacity);
    if (!memory) throw std::bad_alloc();
    staging_.reset(static_cast<char*>(memory));
    stagingBytes_ = capacity;
  }
  return staging_.get();
}

void AppendFiles::dropDirect(OpenFile& file) {
  if (file.directDescriptor >= 0) ::close(file.directDescriptor);
  file.directDescriptor = -1;
}

bool AppendFiles::writeAll(Key key, int descriptor, const char* data, size_t size, int64_t offset) {
  int code = 0;
  const size_t written = writeAt(descriptor, data, size, offset, code);
  if (written == size) return true;
  if (written == 0 && code == EINVAL) return false;   // a direct transfer refused
  throwWriteError(code, fmt::format("{}: cannot write {} bytes at offset {} ({})", pathOf(key).string(), size, offset,
                                    std::strerror(code)));
}

int64_t AppendFiles::end(Key key) const {
  const auto it = files_.find(key);
  return it == files_.end() ? 0 : it->second.end;
}

void AppendFiles::forget(Key key) {
  if (auto it = files_.find(key); it != files_.end()) {
    close(it->second);
    files_.erase(it);
  }
}

void AppendFiles::remove(Key key) {
  forget(key);
  std::error_code ignored;   // already gone is as good
  std::filesystem::remove(pathOf(key), ignored);
}

bool AppendFiles::goesDirect(const OpenFile& file, int64_t offset, int64_t size) {
  return file.directDescriptor >= 0 && size >= kDirectLeastBytes && offset % kDirectAlignment == 0;
}

FileExtent AppendFiles::append(Key key, std::string_view bytes) {
  OpenFile& file = open(key);
  FileExtent extent{file.end, int64_t(bytes.size()), crc32c(bytes.data(), bytes.size())};
  if (goesDirect(file, alignUp(file.end), extent.size)) {
    // From a reused aligned buffer, padded with zeros to whole blocks; the
    // next batch starts after the padding, so that no block is both cached
    // and written directly.
    extent.offset = alignUp(file.end);
    const size_t padded = size_t(alignUp(extent.size));
    char* buffer = staging(padded);
    std::memcpy(buffer, bytes.data(), bytes.size());
    std::memset(buffer + bytes.size(), 0, padded - bytes.size());
    if (writeAll(key, file.directDescriptor, buffer, padded, extent.offset)) {
      file.end = extent.offset + int64_t(padded);
      return extent;
    }
    dropDirect(file);   // the file system refused the transfer: the page cache then
    extent.offset = file.end;
  }
  writeAll(key, file.descriptor, bytes.data(), bytes.size(), extent.offset);
  // Advanced whether or not the caller's transaction commits: a rolled-back
  // batch leaves a gap rather than being overwritten by a committed one.
  file.end = extent.offset + extent.size;
  return extent;
}

int64_t AppendFiles::reserve(Key key, int64_t size, std::string_view head) {
  if (size <= 0 || size % kDirectAlignment != 0 || int64_t(head.size()) > kDirectAlignment)
    throw std::invalid_argument(fmt::format("{}: cannot set aside {} bytes with a head of {}", pathOf(key).string(),
                                            size, head.size()));
  OpenFile& file = open(key);
  const int64_t offset = alignUp(file.end);
  // Through the page cache: the worker reads it within milliseconds (a
  // direct write would send it to the device and the worker's read after
  // it). Its block is its own, so no block is both cached and written
  // directly.
  char block[kDirectAlignment] = {};
  std::memcpy(block, head.data(), head.size());
  writeAll(key, file.descriptor, block, sizeof block, offset);
  // Advanced whether or not the caller's transaction commits, as append.
  file.end = offset + size;
  return offset;
}

std::string AppendFiles::readUnchecked(Key key, const FileExtent& extent) {
  OpenFile& file = open(key);
  if (extent.offset < 0 || extent.size < 0 || extent.offset + extent.size > file.end)
    throw DamagedFileError(fmt::format("{}: {} at offset {} ({} bytes) lies past the end of the file ({} bytes)",
                                       pathOf(key).string(), what_, extent.offset, extent.size, file.end));
  std::string bytes(size_t(extent.size), '\0');
  size_t got = 0;
  int error = 0;
  bool read = false;
  if (goesDirect(file, extent.offset, extent.size)) {
    // Whole blocks into the aligned buffer (the file may end inside the last).
    const size_t blocks = size_t(alignUp(extent.size));
    char* buffer = staging(blocks);
    got = std::min(readAt(file.directDescriptor, buffer, blocks, extent.offset, error), bytes.size());
    std::memcpy(bytes.data(), buffer, got);
    read = error != EINVAL;
    if (!read) dropDirect(file);   // refused: the page cache then
  }
  if (!read) got = readAt(file.descriptor, bytes.data(), bytes.size(), extent.offset, error);
  if (got < bytes.size())
    throw DamagedFileError(fmt::format("{}: {} at offset {} ({} bytes) cannot be read ({})", pathOf(key).string(),
                                       what_, extent.offset, extent.size,
                                       error != 0 ? std::strerror(error) : "file too short"));
  return bytes;
}

std::string AppendFiles::read(Key key, const FileExtent& extent) {
  std::string bytes = readUnchecked(key, extent);
  if (crc32c(bytes.data(), bytes.size()) != extent.crc)
    throw DamagedFileError(fmt::format("{}: {} at offset {} ({} bytes) is damaged (CRC mismatch)",
                                       pathOf(key).string(), what_, extent.offset, extent.size));
  return bytes;
}

}  // namespace portico
