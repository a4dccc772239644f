#include "common/util/file_at.h"

#include <unistd.h>

#include <cerrno>

namespace portico {

size_t readAt(int descriptor, void* out, size_t size, int64_t offset, int& error) {
  char* const bytes = static_cast<char*>(out);
  size_t done = 0;
  error = 0;
  while (done < size) {
    const ssize_t n = ::pread(descriptor, bytes + done, size - done, off_t(offset + int64_t(done)));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) error = errno;
    if (n <= 0) break;
    done += size_t(n);
  }
  return done;
}

size_t writeAt(int descriptor, const void* data, size_t size, int64_t offset, int& error) {
  const char* const bytes = static_cast<const char*>(data);
  size_t done = 0;
  error = 0;
  while (done < size) {
    const ssize_t n = ::pwrite(descriptor, bytes + done, size - done, off_t(offset + int64_t(done)));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      error = n < 0 ? errno : ENOSPC;   // no progress: nothing more fits
      break;
    }
    done += size_t(n);
  }
  return done;
}

}  // namespace portico
