#include "coordinator/append_files.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <system_error>

#include <fmt/format.h>

#include "common/util/crc32c.h"

namespace portico {

namespace {
// Full, over quota, or failing: space or the device may come back.
[[noreturn]] void throwWriteError(int code, const std::string& what) {
  if (code == ENOSPC || code == EDQUOT || code == EIO) throw DiskWriteError(what);
  throw std::runtime_error(what);
}
}  // namespace

AppendFiles::AppendFiles(std::filesystem::path directory, Naming naming, std::string what,
                         std::function<int64_t(Key)> committedEnd)
    : directory_(std::move(directory)), naming_(naming), what_(std::move(what)), committedEnd_(std::move(committedEnd)) {}

AppendFiles::~AppendFiles() {
  for (auto& [key, file] : files_) ::close(file.descriptor);
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
  return files_[key] = OpenFile{descriptor, end};
}

int64_t AppendFiles::end(Key key) const {
  const auto it = files_.find(key);
  return it == files_.end() ? 0 : it->second.end;
}

void AppendFiles::forget(Key key) {
  if (auto it = files_.find(key); it != files_.end()) {
    ::close(it->second.descriptor);
    files_.erase(it);
  }
}

void AppendFiles::remove(Key key) {
  forget(key);
  std::error_code ignored;   // already gone is as good
  std::filesystem::remove(pathOf(key), ignored);
}

FileExtent AppendFiles::append(Key key, std::string_view bytes) {
  OpenFile& file = open(key);
  FileExtent extent{file.end, int64_t(bytes.size()), crc32c(bytes.data(), bytes.size())};
  size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t n = ::pwrite(file.descriptor, bytes.data() + written, bytes.size() - written,
                               off_t(extent.offset + int64_t(written)));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int code = n < 0 ? errno : ENOSPC;   // no progress: nothing more fits
      throwWriteError(code, fmt::format("{}: cannot write {} bytes at offset {} ({})", pathOf(key).string(),
                                        bytes.size(), extent.offset, std::strerror(code)));
    }
    written += size_t(n);
  }
  // Advanced whether or not the caller's transaction commits: a rolled-back
  // batch leaves a gap rather than being overwritten by a committed one.
  file.end += extent.size;
  return extent;
}

std::string AppendFiles::readUnchecked(Key key, const FileExtent& extent) {
  OpenFile& file = open(key);
  if (extent.offset < 0 || extent.size < 0 || extent.offset + extent.size > file.end)
    throw DamagedFileError(fmt::format("{}: {} at offset {} ({} bytes) lies past the end of the file ({} bytes)",
                                       pathOf(key).string(), what_, extent.offset, extent.size, file.end));
  std::string bytes(size_t(extent.size), '\0');
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::pread(file.descriptor, bytes.data() + done, bytes.size() - done, off_t(extent.offset + int64_t(done)));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0)
      throw DamagedFileError(fmt::format("{}: {} at offset {} ({} bytes) cannot be read ({})", pathOf(key).string(), what_,
                                         extent.offset, extent.size, n < 0 ? std::strerror(errno) : "file too short"));
    done += size_t(n);
  }
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
