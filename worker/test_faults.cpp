#include "worker/test_faults.h"

#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

namespace portico {

namespace {
const std::string& testFault() {
  static const std::string fault = [] {
    const char* value = std::getenv("PORTICO_TEST_FAULT");
    const std::string name = value ? value : "";
    if (!name.empty()) spdlog::warn("PORTICO_TEST_FAULT={}: this worker sends bad Results on purpose", name);
    return name;
  }();
  return fault;
}
}  // namespace

void applyTestFault(KernelOutputs& out, bool renderLease) {
  const std::string& fault = testFault();
  if (fault == "zero-deposits") {
    for (auto& [cell, records] : out.deposits) std::memset(records.data(), 0, records.size() * sizeof(PhotonRecord));
    TraceCounters& c = out.counters;
    c.photonsEmitted = c.photonDeposits = c.photonsAbsorbed = c.photonsEscaped = c.photonCrossings = c.photonCopies = 0;
  } else if (fault == "drop-crossings") {
    out.crossings.clear();
  } else if (fault == "duplicate-crossings" && renderLease) {
    for (auto& [cell, rays] : out.crossings) {
      const std::vector<RayState> copy = rays;
      rays.insert(rays.end(), copy.begin(), copy.end());
    }
  } else if (fault == "drop-render-crossings" && renderLease) {
    out.crossings.clear();
  } else if (fault == "uncounted-rays" && renderLease) {
    TraceCounters& c = out.counters;
    c.emissionRays = c.shadowRays = c.gatherRays = c.raysFinished = 0;
  }
}

void stallIfTestFault() {
  const std::string& fault = testFault();
  if (fault != "hang-in-lease" && fault != "stall-in-lease" && fault != "busy-in-lease") return;
  static std::atomic<bool> stalled{false};
  if (stalled.exchange(true)) return;   // the first lease only
  spdlog::warn("PORTICO_TEST_FAULT={}: this lease's tracing thread stops moving", fault);
  if (fault == "busy-in-lease") {
    // Works for 4 s without counting (as a long accelerator build does).
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(4);
    volatile uint64_t spins = 0;
    while (std::chrono::steady_clock::now() < until) spins = spins + 1;
    return;
  }
  if (fault == "stall-in-lease") {
    std::this_thread::sleep_for(std::chrono::seconds(4));
    return;
  }
  for (;;) std::this_thread::sleep_for(std::chrono::hours(1));
}

void applyTestFault(wire::Result::Builder result) {
  if (testFault() != "negative-film") return;
  for (auto pixel : result.getFilm()) {
    pixel.setR(-1 - pixel.getR());
    pixel.setG(-1 - pixel.getG());
    pixel.setB(-1 - pixel.getB());
  }
}

}  // namespace portico
