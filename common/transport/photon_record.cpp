#include "common/transport/photon_record.h"

#include <fmt/format.h>

#include <stdexcept>

namespace portico {

void unpackRecords(const void* bytes, size_t size, bool includeDirect, std::vector<StoredPhoton>& out) {
  if (size % sizeof(PhotonRecord) != 0)
    throw std::runtime_error(fmt::format("photon table: {} bytes is not a whole number of {}-byte records", size,
                                         sizeof(PhotonRecord)));
  const size_t count = size / sizeof(PhotonRecord);
  out.reserve(out.size() + count);
  for (size_t i = 0; i < count; ++i) {
    PhotonRecord r;
    std::memcpy(&r, static_cast<const char*>(bytes) + i * sizeof r, sizeof r);
    if (r.bounce == 0 && !includeDirect) continue;
    StoredPhoton p = fromRecord(r);
    if (isFinite(p.position) && isFinite(p.power)) out.push_back(p);
  }
}

}  // namespace portico
