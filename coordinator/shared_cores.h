// Threads sharing a machine's cores, for the cluster model: the kernel's
// fair scheduler idealised as processor sharing. While k threads want a
// core, each runs at min(1, cores / k) of one; with cores = 0 every thread
// has a core of its own (a cluster: a machine per worker). Each thread runs
// one burst of CPU at a time; a burst's end is found on a shared service
// clock (the CPU each running thread has had), so a step costs O(log k)
// whatever the number of threads.
#pragma once

#include <cstddef>
#include <functional>
#include <queue>
#include <utility>
#include <vector>

namespace portico {

class SharedCores {
 public:
  explicit SharedCores(double cores) : cores_(cores) {}

  // Thread `id` (not running) starts a burst of `cpuSeconds`.
  void start(size_t id, double cpuSeconds) { ends_.push({served_ + cpuSeconds, id}); }
  bool idle() const { return ends_.empty(); }
  size_t running() const { return ends_.size(); }

  // When, from `now`, the next burst ends if no burst starts before
  // (infinity when none runs).
  double nextEnd(double now) const;

  // From `now` to `to` (at most nextEnd(now)): the threads whose bursts
  // ended by then, in the order they ended.
  std::vector<size_t> advance(double now, double to);

 private:
  double rate() const;   // the share of a core each running thread has
  double cores_;
  double served_ = 0;
  std::priority_queue<std::pair<double, size_t>, std::vector<std::pair<double, size_t>>, std::greater<>> ends_;
};

}  // namespace portico
