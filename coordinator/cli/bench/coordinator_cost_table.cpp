#include "coordinator/cli/bench/coordinator_cost_table.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace portico::cli {

namespace {
std::vector<std::string> fields(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream in(line);
  for (std::string field; std::getline(in, field, ',');) out.push_back(field);
  return out;
}
}  // namespace

CoordinatorCostTable::CoordinatorCostTable(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument(fmt::format("{}: cannot be read", path));
  std::string line;
  if (!std::getline(in, line)) throw std::invalid_argument(fmt::format("{}: empty", path));
  std::map<std::string, size_t> column;
  const auto header = fields(line);
  for (size_t i = 0; i < header.size(); ++i) column[header[i]] = i;
  for (const char* name : {"workers", "coordinator_cpu_ms_per_lease", "bytes_per_work"})
    if (!column.count(name))
      throw std::invalid_argument(
          fmt::format("{}:1: no column {} (a CSV of `portico bench coordinator --csv`)", path, name));
  for (int number = 2; std::getline(in, line); ++number) {
    const auto row = fields(line);
    try {
      Row r{std::stod(row.at(column["workers"])), {std::stod(row.at(column["coordinator_cpu_ms_per_lease"])) * 1e-3}};
      const double all = std::stod(row.at(column["bytes_per_work"]));
      const char* phaseColumns[2] = {"bytes_per_photon_work", "bytes_per_render_work"};
      for (int phase : {0, 1})
        r.cost.bytesPerWork[phase] =
            column.count(phaseColumns[phase]) ? std::stod(row.at(column[phaseColumns[phase]])) : all;
      if (!(r.workers >= 1) || !(r.cost.cpuSecondsPerLease >= 0) || !(r.cost.bytesPerWork[0] >= 0) ||
          !(r.cost.bytesPerWork[1] >= 0))
        throw std::invalid_argument("negative or no workers");
      rows_.push_back(r);
    } catch (const std::exception& e) {
      throw std::invalid_argument(fmt::format("{}:{}: not a row of workers and costs ({})", path, number, e.what()));
    }
  }
  if (rows_.empty()) throw std::invalid_argument(fmt::format("{}: no rows", path));
  std::sort(rows_.begin(), rows_.end(), [](const Row& a, const Row& b) { return a.workers < b.workers; });
}

CoordinatorCost CoordinatorCostTable::at(size_t workers) const {
  const double n = double(workers);
  if (n <= rows_.front().workers) return rows_.front().cost;
  if (n >= rows_.back().workers) return rows_.back().cost;
  const auto above = std::find_if(rows_.begin(), rows_.end(), [&](const Row& r) { return r.workers >= n; });
  const auto below = above - 1;
  const double f = std::log(n / below->workers) / std::log(above->workers / below->workers);
  const auto between = [f](double a, double b) { return a + f * (b - a); };
  CoordinatorCost cost;
  cost.cpuSecondsPerLease = between(below->cost.cpuSecondsPerLease, above->cost.cpuSecondsPerLease);
  for (int phase : {0, 1}) cost.bytesPerWork[phase] = between(below->cost.bytesPerWork[phase], above->cost.bytesPerWork[phase]);
  return cost;
}

}  // namespace portico::cli
