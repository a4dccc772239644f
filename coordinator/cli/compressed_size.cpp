// zlibCompressedSize: a streaming deflate whose output is only counted.
#include "coordinator/cli/compressed_size.h"

#include <fmt/format.h>
#include <zlib.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <vector>

namespace portico::cli {

uint64_t zlibCompressedSize(const std::string& path) {
  const auto fail = [&](const std::string& problem) {
    return std::runtime_error(fmt::format("{}: cannot compress: {}", path, problem));
  };
  const std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw fail(std::strerror(errno));

  z_stream stream{};
  if (deflateInit(&stream, Z_DEFAULT_COMPRESSION) != Z_OK) throw fail("zlib could not start");
  const std::unique_ptr<z_stream, int (*)(z_stream*)> end(&stream, &deflateEnd);
  constexpr size_t kChunk = size_t{1} << 20;
  std::vector<unsigned char> in(kChunk), out(kChunk);
  uint64_t compressed = 0;
  int flush = Z_NO_FLUSH;
  while (flush != Z_FINISH) {
    const size_t read = std::fread(in.data(), 1, in.size(), file.get());
    if (std::ferror(file.get())) throw fail(std::strerror(errno));
    flush = std::feof(file.get()) ? Z_FINISH : Z_NO_FLUSH;
    stream.next_in = in.data();
    stream.avail_in = static_cast<uInt>(read);
    do {   // drain: deflate may produce more than one buffer per input chunk
      stream.next_out = out.data();
      stream.avail_out = static_cast<uInt>(out.size());
      if (deflate(&stream, flush) == Z_STREAM_ERROR) throw fail("zlib stream error");
      compressed += out.size() - stream.avail_out;
    } while (stream.avail_out == 0);
  }
  return compressed;
}

}  // namespace portico::cli
