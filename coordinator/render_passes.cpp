#include "coordinator/render_passes.h"

#include <cstring>
#include <span>
#include <stdexcept>

#include "common/rng.h"
#include "coordinator/pass_error.h"

namespace portico {

const char* toString(PassStop stop) {
  switch (stop) {
    case PassStop::TargetMet: return "target_met";
    case PassStop::TimeLimit: return "time_limit";
    case PassStop::MaxPasses: return "max_passes";
    case PassStop::None: break;
  }
  return "";
}

uint64_t passSeed(uint64_t seed, uint32_t index) {
  if (index == 0) return seed;
  return mix64(mix64(seed ^ 0x70617373ull) + index);   // "pass"
}

namespace {
std::vector<double> doublesOf(std::span<const uint8_t> blob) {
  std::vector<double> values(blob.size() / sizeof(double));
  if (!values.empty()) std::memcpy(values.data(), blob.data(), values.size() * sizeof(double));
  return values;
}

PassBlockStatistics loadBlockStatistics(sql::Database& db, uint64_t job) {
  PassBlockStatistics statistics;
  auto& s = db.prepare("SELECT block_sums, block_deviations FROM render_progress WHERE job = ?");
  s.bind(1, int64_t(job));
  if (s.step()) {
    statistics.sums = doublesOf(s.columnBlob(0));
    statistics.deviations = doublesOf(s.columnBlob(1));
  }
  s.reset();
  return statistics;
}

void saveProgress(sql::Database& db, uint64_t job, uint32_t passesStarted, PassStop stop,
                  const PassBlockStatistics& statistics) {
  auto& s = db.prepare(
      "INSERT INTO render_progress(job, passes_started, stop_reason, block_sums, block_deviations) "
      "VALUES (?, ?, ?, ?, ?) ON CONFLICT(job) DO UPDATE SET passes_started = excluded.passes_started, "
      "stop_reason = excluded.stop_reason, block_sums = excluded.block_sums, "
      "block_deviations = excluded.block_deviations");
  s.bind(1, int64_t(job)).bind(2, int64_t(passesStarted)).bind(3, std::string_view(toString(stop)));
  s.bindBlob(4, statistics.sums.data(), statistics.sums.size() * sizeof(double));
  s.bindBlob(5, statistics.deviations.data(), statistics.deviations.size() * sizeof(double));
  s.run();
}
}  // namespace

RenderProgress loadRenderProgress(sql::Database& db, uint64_t job) {
  RenderProgress progress;
  auto& row = db.prepare("SELECT passes_started, stop_reason FROM render_progress WHERE job = ?");
  row.bind(1, int64_t(job));
  if (row.step()) {
    progress.passesStarted = uint32_t(row.columnInt(0));
    progress.stopReason = row.columnText(1);
  }
  row.reset();
  auto& passes = db.prepare("SELECT pass, finished_ms, error_estimate FROM render_passes WHERE job = ? ORDER BY pass");
  passes.bind(1, int64_t(job));
  while (passes.step()) {
    RenderPassRecord pass{uint32_t(passes.columnInt(0)), passes.columnInt(1), std::nullopt};
    if (!passes.columnIsNull(2)) pass.errorEstimate = passes.columnDouble(2);
    progress.passes.push_back(pass);
  }
  passes.reset();
  return progress;
}

PassStop stopAfterPass(wire::JobSpec::Reader spec, std::optional<double> errorEstimate,
                       const std::vector<int64_t>& passEndsMs) {
  const auto done = uint32_t(passEndsMs.size());
  if (spec.getTargetError().isValue() && errorEstimate && *errorEstimate <= spec.getTargetError().getValue())
    return PassStop::TargetMet;
  if (done >= spec.getMaxPasses()) return PassStop::MaxPasses;
  if (spec.getTimeLimit().isSeconds()) {
    // The first pass also builds every photon map the render reads: the
    // passes after it predict the next one better, when there are any.
    const int64_t elapsed = passEndsMs.back();
    const double nextMs = done >= 2 ? double(elapsed - passEndsMs.front()) / (done - 1) : double(elapsed);
    if (double(elapsed) + nextMs > spec.getTimeLimit().getSeconds() * 1000.0) return PassStop::TimeLimit;
  }
  return PassStop::None;
}

PassEnd endRenderPass(JobStore& store, const JobRecord& job, wire::JobSpec::Reader spec, int64_t nowMs) {
  sql::Database& db = store.database();
  RenderProgress progress = loadRenderProgress(db, job.id);
  PassEnd end;
  end.pass = progress.passesStarted;
  if (progress.passesDone() >= progress.passesStarted) {
    // Recorded, then the coordinator stopped before the job was finished.
    if (progress.stopReason.empty())
      throw std::logic_error("render pass recorded as done with neither a next pass nor a stop reason");
    end.recordedBefore = true;
    end.errorEstimate = progress.passes.empty() ? std::nullopt : progress.passes.back().errorEstimate;
    end.stop = progress.stopReason == toString(PassStop::TargetMet)   ? PassStop::TargetMet
               : progress.stopReason == toString(PassStop::TimeLimit) ? PassStop::TimeLimit
                                                                      : PassStop::MaxPasses;
    return end;
  }
  // A job of one pass has nothing to estimate, and no later pass needs its blocks.
  PassBlockStatistics statistics;
  if (spec.getMaxPasses() > 1) {
    statistics = loadBlockStatistics(db, job.id);
    const uint64_t pixels = uint64_t(spec.getWidth()) * spec.getHeight();
    end.errorEstimate =
        addPassAndEstimate(store.film(job.id, pixels), spec.getWidth(), spec.getHeight(), end.pass, statistics).estimate;
  }
  auto& record = db.prepare("INSERT INTO render_passes(job, pass, finished_ms, error_estimate) VALUES (?, ?, ?, ?)");
  record.bind(1, int64_t(job.id)).bind(2, int64_t(end.pass)).bind(3, nowMs);
  if (end.errorEstimate) record.bind(4, *end.errorEstimate);
  else record.bindNull(4);
  record.run();
  std::vector<int64_t> passEndsMs;
  for (const RenderPassRecord& pass : progress.passes) passEndsMs.push_back(pass.finishedMs - job.phaseStartedMs);
  passEndsMs.push_back(nowMs - job.phaseStartedMs);
  end.stop = stopAfterPass(spec, end.errorEstimate, passEndsMs);
  saveProgress(db, job.id, end.stop == PassStop::None ? end.pass + 1 : end.pass, end.stop, statistics);
  return end;
}

}  // namespace portico
