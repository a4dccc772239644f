#include "coordinator/shared_cores.h"

#include <algorithm>
#include <limits>

namespace portico {

double SharedCores::rate() const {
  if (cores_ <= 0 || ends_.empty()) return 1;
  return std::min(1.0, cores_ / double(ends_.size()));
}

double SharedCores::nextEnd(double now) const {
  if (ends_.empty()) return std::numeric_limits<double>::infinity();
  return now + std::max(0.0, ends_.top().first - served_) / rate();
}

std::vector<size_t> SharedCores::advance(double now, double to) {
  std::vector<size_t> ended;
  if (ends_.empty()) return ended;
  served_ += rate() * std::max(0.0, to - now);
  // Rounding: a burst due at `to` ends there, not a hair later.
  const double slack = 1e-12 * std::max(1.0, served_);
  while (!ends_.empty() && ends_.top().first <= served_ + slack) {
    ended.push_back(ends_.top().second);
    ends_.pop();
  }
  return ended;
}

}  // namespace portico
