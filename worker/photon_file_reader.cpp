#include "worker/photon_file_reader.h"

#include <fcntl.h>
#include <unistd.h>

#include <fmt/format.h>

#include <cerrno>
#include <cstring>

#include "common/util/crc32c.h"

namespace portico {

bool namesPhotonFile(wire::PhotonsReply::Reader reply) { return reply.hasFile() && reply.getFile().size() > 0; }

std::optional<std::string> readPhotonFile(wire::PhotonsReply::Reader reply, std::string& why) {
  const std::string path = reply.getFile().cStr();
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    why = fmt::format("{}: {}", path, std::strerror(errno));
    return std::nullopt;
  }
  size_t size = 0;
  for (auto extent : reply.getExtents()) size += extent.getSize();
  std::string records(size, '\0');
  size_t at = 0;
  for (auto extent : reply.getExtents()) {
    size_t done = 0;
    while (done < extent.getSize()) {
      const ssize_t n = ::pread(fd, records.data() + at + done, extent.getSize() - done,
                                off_t(extent.getOffset() + done));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        why = n < 0 ? fmt::format("{}: {}", path, std::strerror(errno))
                    : fmt::format("{}: ends before byte {}", path, extent.getOffset() + extent.getSize());
        ::close(fd);
        return std::nullopt;
      }
      done += size_t(n);
    }
    if (crc32c(records.data() + at, extent.getSize()) != extent.getCrc()) {
      why = fmt::format("{}: the {} bytes at {} are not those the coordinator recorded", path, extent.getSize(),
                        extent.getOffset());
      ::close(fd);
      return std::nullopt;
    }
    at += extent.getSize();
  }
  ::close(fd);
  return records;
}

}  // namespace portico
