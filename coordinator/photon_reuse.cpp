#include "coordinator/photon_reuse.h"

#include <fmt/format.h>
#include <sys/stat.h>

#include <fstream>
#include <stdexcept>

#include "common/rng.h"
#include "common/transport/photon_record.h"
#include "common/util/crc32c.h"

namespace portico {

namespace {
// Folds a file's identity into `hash`. A file that cannot be read gives an
// error: the job is refused at submit as it would be at its first lease.
uint64_t foldFileIdentity(uint64_t hash, const std::string& path) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0) throw std::runtime_error(fmt::format("{}: cannot be read", path));
  for (uint64_t value :
       {uint64_t(info.st_dev), uint64_t(info.st_ino), uint64_t(info.st_size), uint64_t(info.st_mtim.tv_sec),
        uint64_t(info.st_mtim.tv_nsec), uint64_t(info.st_ctim.tv_sec), uint64_t(info.st_ctim.tv_nsec)})
    hash = mix64(hash ^ value);
  return hash;
}

uint32_t contentCrc(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(fmt::format("{}: cannot be read", path));
  uint32_t crc = 0;
  char buffer[1 << 16];
  while (in.read(buffer, sizeof buffer) || in.gcount() > 0) crc = crc32c(buffer, size_t(in.gcount()), crc);
  return crc;
}
}  // namespace

// Cell files are identified by their metadata, not hashed: a store's cells
// are gigabytes, and a regenerated store writes new files (SceneStoreWriter
// renames a new directory into place), which have new inodes.
std::string storeFingerprint(const SceneStore& scene) {
  uint64_t hash = foldFileIdentity(0, scene.cataloguePath());
  for (uint32_t cell = 0; cell < scene.cells().size(); ++cell) hash = foldFileIdentity(hash, scene.cellPath(cell));
  return fmt::format("{:016x}-{:08x}", hash, contentCrc(scene.cataloguePath()));
}

std::string photonPassKey(const JobSettings& resolved, const SceneStore& scene) {
  if (resolved.aov != JobSettings::Aov::Radiance) return "";
  std::string key = fmt::format("store={} content={} photons={} seed={} accel={} radius={:a} bounces={} record={}",
                                scene.directory(), storeFingerprint(scene), resolved.photons, resolved.seed,
                                resolved.accel, resolved.photonRadius, resolved.maxPhotonBounces, sizeof(PhotonRecord));
  // Daylight's photons depend on all of its settings; a job without any
  // keeps the key it always had.
  if (const DaylightSettings& d = resolved.daylight; d.any())
    key += fmt::format(" sky={} sky_radiance={:a},{:a},{:a} turbidity={:a} sun={} azimuth={:a} elevation={:a} "
                       "sun_irradiance={:a},{:a},{:a}",
                       int(d.sky), d.skyRadiance.x, d.skyRadiance.y, d.skyRadiance.z, d.turbidity, d.sun,
                       d.sunAzimuthDegrees, d.sunElevationDegrees, d.sunIrradiance.x, d.sunIrradiance.y,
                       d.sunIrradiance.z);
  // A daylight-factor analysis leaves the lamps off (lampsLit): other
  // photons, and another power unit (photon_power_unit.h).
  if (!lampsLit(resolved)) key += " lamps=off";
  return key;
}

}  // namespace portico
