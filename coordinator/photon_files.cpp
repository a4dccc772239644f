#include "coordinator/photon_files.h"

#include <fcntl.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <system_error>

#include <fmt/format.h>

namespace portico {

namespace {

uint32_t crcOf(const char* data, size_t size) {
  uLong crc = crc32(0L, Z_NULL, 0);
  // zlib takes lengths as uInt: feed it in pieces below 4 GiB.
  while (size > 0) {
    const uInt piece = uInt(std::min<size_t>(size, size_t(1) << 30));
    crc = crc32(crc, reinterpret_cast<const Bytef*>(data), piece);
    data += piece;
    size -= piece;
  }
  return uint32_t(crc);
}

}  // namespace

PhotonFiles::PhotonFiles(std::filesystem::path directory, std::function<int64_t(uint64_t job)> committedEnd)
    : directory_(std::move(directory)), committedEnd_(std::move(committedEnd)) {}

PhotonFiles::~PhotonFiles() {
  for (auto& [job, file] : files_) ::close(file.descriptor);
}

std::filesystem::path PhotonFiles::pathOf(uint64_t job) const {
  return directory_ / fmt::format("job-{}.bin", job);
}

PhotonFiles::OpenFile& PhotonFiles::open(uint64_t job) {
  if (auto it = files_.find(job); it != files_.end()) return it->second;
  std::error_code error;
  std::filesystem::create_directories(directory_, error);
  if (error) throw std::runtime_error(fmt::format("{}: cannot be created ({})", directory_.string(), error.message()));
  const std::string path = pathOf(job).string();
  const int descriptor = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (descriptor < 0) throw std::runtime_error(fmt::format("{}: cannot be opened ({})", path, std::strerror(errno)));
  // Bytes past the last recorded batch belong to Results that never
  // committed: drop them, and write from there.
  const int64_t end = committedEnd_(job);
  if (::ftruncate(descriptor, end) != 0) {
    const int code = errno;
    ::close(descriptor);
    throw std::runtime_error(fmt::format("{}: cannot be cut to {} bytes ({})", path, end, std::strerror(code)));
  }
  return files_[job] = OpenFile{descriptor, end};
}

void PhotonFiles::forget(uint64_t job) {
  if (auto it = files_.find(job); it != files_.end()) {
    ::close(it->second.descriptor);
    files_.erase(it);
  }
}

PhotonExtent PhotonFiles::append(uint64_t job, std::string_view bytes) {
  OpenFile& file = open(job);
  PhotonExtent extent{file.end, int64_t(bytes.size()), crcOf(bytes.data(), bytes.size())};
  size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t n = ::pwrite(file.descriptor, bytes.data() + written, bytes.size() - written,
                               off_t(extent.offset + int64_t(written)));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0)
      throw std::runtime_error(fmt::format("{}: cannot write {} bytes at offset {} ({})", pathOf(job).string(),
                                           bytes.size(), extent.offset, n < 0 ? std::strerror(errno) : "no progress"));
    written += size_t(n);
  }
  // Advanced whether or not the caller's transaction commits: a rolled-back
  // batch leaves a gap rather than being overwritten by a committed one.
  file.end += extent.size;
  return extent;
}

std::string PhotonFiles::read(uint64_t job, const PhotonExtent& extent) {
  OpenFile& file = open(job);
  const std::string path = pathOf(job).string();
  if (extent.offset < 0 || extent.size < 0 || extent.offset + extent.size > file.end)
    throw std::runtime_error(fmt::format("{}: photon batch at offset {} ({} bytes) lies past the end of the file ({} bytes)",
                                         path, extent.offset, extent.size, file.end));
  std::string bytes(size_t(extent.size), '\0');
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::pread(file.descriptor, bytes.data() + done, bytes.size() - done, off_t(extent.offset + int64_t(done)));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0)
      throw std::runtime_error(fmt::format("{}: photon batch at offset {} ({} bytes) cannot be read ({})", path,
                                           extent.offset, extent.size, n < 0 ? std::strerror(errno) : "file too short"));
    done += size_t(n);
  }
  if (crcOf(bytes.data(), bytes.size()) != extent.crc)
    throw std::runtime_error(fmt::format("{}: photon batch at offset {} ({} bytes) is damaged (CRC mismatch)", path,
                                         extent.offset, extent.size));
  return bytes;
}

}  // namespace portico
