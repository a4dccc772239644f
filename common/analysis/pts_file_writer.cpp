#include "common/analysis/pts_file_writer.h"

#include <fmt/format.h>

#include "common/util/atomic_file.h"

namespace portico {

std::string ptsText(const std::vector<Sensor>& sensors) {
  std::string text;
  text.reserve(sensors.size() * 48);
  for (const Sensor& s : sensors)
    fmt::format_to(std::back_inserter(text), "{} {} {} {} {} {}\n", s.position.x, s.position.y, s.position.z,
                   s.direction.x, s.direction.y, s.direction.z);
  return text;
}

void writePtsFile(const std::string& path, const std::vector<Sensor>& sensors) {
  writeFileAtomically(path, ptsText(sensors));
}

}  // namespace portico
