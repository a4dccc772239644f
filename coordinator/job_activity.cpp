#include "coordinator/job_activity.h"

#include <algorithm>
#include <cstdlib>
#include <map>
#include <set>

namespace portico {

nlohmann::json cellActivity(JobStore& store, const JobRecord& job, const WorkerRegistry& workers) {
  const int phase = phaseOf(job.state);
  struct Cell {
    int64_t pending = 0, loads = 0;
    std::set<std::string> leasedBy;
    bool done = false;
  };
  std::map<uint32_t, Cell> cells;
  if (isActive(job.state))
    for (const auto& [cell, work] : store.pendingWorkByCell(job.id, phase, SIZE_MAX >> 1)) cells[cell].pending = work;
  for (const auto& [identity, worker] : workers)
    for (const auto& [lease, inFlight] : worker.leases)
      if (inFlight.job == job.id) {
        cells[inFlight.cell].leasedBy.insert(worker.name);
        for (const auto& [more, work] : inFlight.moreCellWork) cells[more].leasedBy.insert(worker.name);
      }
  for (const LeaseLogEntry& entry : store.leaseLog(job.id)) {
    if (isActive(job.state) && entry.phase != phase) continue;
    cells[entry.cell].done = true;
    for (const auto& [more, work] : entry.moreCellWork) cells[more].done = true;
  }
  const std::string loadPrefix = "accel.cell.";
  const auto counters = store.counters(job.id);
  for (auto it = counters.lower_bound(loadPrefix); it != counters.end() && it->first.rfind(loadPrefix, 0) == 0; ++it)
    cells[uint32_t(std::strtoul(it->first.c_str() + loadPrefix.size(), nullptr, 10))].loads += it->second;
  nlohmann::json list = nlohmann::json::array();
  for (const auto& [id, cell] : cells)
    list.push_back({{"cell", id},
                    {"pending", cell.pending},
                    {"leased_by", cell.leasedBy},
                    {"done", cell.done && cell.pending == 0},
                    {"loads", cell.loads}});
  return {{"job", job.id}, {"phase", phase == 0 ? "photons" : "render"}, {"cells", list}};
}

LinearImage shrinkImage(const LinearImage& film, uint32_t maxSide) {
  const uint32_t side = maxSide == 0 ? kMaxPreviewSide : std::min(maxSide, kMaxPreviewSide);
  const uint32_t longest = std::max(film.width, film.height);
  const uint32_t factor = std::max<uint32_t>(1, (longest + side - 1) / side);
  LinearImage small;
  small.width = (film.width + factor - 1) / factor;
  small.height = (film.height + factor - 1) / factor;
  small.rgb.assign(size_t(small.width) * small.height * 3, 0.0f);
  std::vector<uint32_t> counts(size_t(small.width) * small.height, 0);
  for (uint32_t y = 0; y < film.height; ++y)
    for (uint32_t x = 0; x < film.width; ++x) {
      const size_t to = size_t(y / factor) * small.width + x / factor, from = size_t(y) * film.width + x;
      for (int c = 0; c < 3; ++c) small.rgb[3 * to + c] += film.rgb[3 * from + c];
      ++counts[to];
    }
  for (size_t p = 0; p < counts.size(); ++p)
    for (int c = 0; c < 3; ++c) small.rgb[3 * p + c] /= float(std::max<uint32_t>(1, counts[p]));
  return small;
}

}  // namespace portico
